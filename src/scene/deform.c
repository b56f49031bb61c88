/* Skinning and morph targets: an instance's vertices at a time, written once for both backends
 * (prep/deform_keys.c samples it per segment). Morph targets apply first, in the mesh's space,
 * then the skin (glTF's order); skin matrices are blended linearly (linear blend skinning, as
 * glTF and every exporter assume). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"

int evr_instance_deforms(const evr_scene *s, int instance)
{
    if (!s || instance < 0 || instance >= s->num_instances) return 0;
    const evr_mesh *m = &s->meshes[s->instances[instance].mesh];
    return m->skin != NULL || m->morph != NULL;
}

int evr_instance_deform_animated(const evr_scene *s, int instance)
{
    if (!evr_instance_deforms(s, instance)) return 0;
    const evr_instance *in = &s->instances[instance];
    const evr_mesh *m = &s->meshes[in->mesh];
    if (m->morph && in->node >= 0 && in->node < s->num_nodes &&
        s->nodes[in->node].w_curve.num_keys > 1)
        return 1;
    if (m->skin)
        for (int j = 0; j < m->skin->num_joints; j++)
            if (evr_node_chain_animated(s, m->skin->joint_nodes[j])) return 1;
    return 0;
}

void evr_node_weights_at(const evr_node *n, double t, float *w)
{
    const evr_curve *c = &n->w_curve;
    const int d = n->num_weights;
    if (d <= 0) return;
    if (c->num_keys <= 0) {
        memcpy(w, n->weights, sizeof *w * (size_t)d);
        return;
    }
    const int last = c->num_keys - 1;
    if (c->num_keys == 1 || t <= c->times[0]) {
        memcpy(w, c->values, sizeof *w * (size_t)d);
        return;
    }
    if (t >= c->times[last]) {
        memcpy(w, c->values + (size_t)last * (size_t)d, sizeof *w * (size_t)d);
        return;
    }
    int lo = 0, hi = last; /* times[lo] <= t < times[hi] */
    while (hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        if (c->times[mid] <= t) lo = mid;
        else hi = mid;
    }
    const float *a = c->values + (size_t)lo * (size_t)d, *b = a + d;
    const double dt = c->times[lo + 1] - c->times[lo];
    /* a value held between equal keys is held exactly (see anim.c) */
    if (c->interp == EVR_INTERP_STEP || dt <= 0.0 || !memcmp(a, b, sizeof *a * (size_t)d)) {
        memcpy(w, a, sizeof *w * (size_t)d);
        return;
    }
    const float f = (float)((t - c->times[lo]) / dt);
    for (int j = 0; j < d; j++) w[j] = a[j] + (b[j] - a[j]) * f;
}

/* Joint matrices at time t: world(joint) * inverse bind. */
static void joint_matrices(const evr_scene *s, const evr_skin *sk, double t, evr_m34 *out)
{
    for (int j = 0; j < sk->num_joints; j++) {
        const evr_m34 w = evr_node_world_at(s, sk->joint_nodes[j], t);
        out[j] = evr_m34_mul(w, sk->inverse_bind[j]);
    }
}

int evr_instance_deformed_at(const evr_scene *s, int instance, double t, float *positions,
                             float *normals)
{
    return evr_instance_deformed_range(
        s, instance, t, 0, s->meshes[s->instances[instance].mesh].num_vertices, positions, normals);
}

int evr_instance_deformed_range(const evr_scene *s, int instance, double t, uint32_t first,
                                uint32_t end, float *positions, float *normals)
{
    const evr_instance *in = &s->instances[instance];
    const evr_mesh *m = &s->meshes[in->mesh];
    const size_t v0 = first, nv = end; /* vertices [v0, nv) */
    memcpy(positions + 3 * v0, m->positions + 3 * v0, sizeof(float) * 3 * (nv - v0));
    if (normals) memcpy(normals + 3 * v0, m->normals + 3 * v0, sizeof(float) * 3 * (nv - v0));
    if (m->morph && in->node >= 0 && in->node < s->num_nodes) {
        const evr_morph *mo = m->morph;
        const evr_node *n = &s->nodes[in->node];
        float wstack[16], *w = wstack;
        if (mo->num_targets > 16 && !(w = malloc(sizeof *w * (size_t)mo->num_targets))) return 0;
        {
            const int nw = n->num_weights < mo->num_targets ? n->num_weights : mo->num_targets;
            for (int j = 0; j < mo->num_targets; j++) w[j] = mo->default_weights[j];
            if (nw > 0) {
                float nodew_stack[16], *nodew = nodew_stack;
                if (n->num_weights > 16 &&
                    !(nodew = malloc(sizeof *nodew * (size_t)n->num_weights))) {
                    if (w != wstack) free(w);
                    return 0;
                }
                evr_node_weights_at(n, t, nodew);
                memcpy(w, nodew, sizeof *w * (size_t)nw);
                if (nodew != nodew_stack) free(nodew);
            }
            for (int j = 0; j < mo->num_targets; j++) {
                if (w[j] == 0.0f) continue;
                const size_t all = m->num_vertices;
                const float *dp = mo->d_positions + (size_t)j * 3 * all;
                for (size_t k = 3 * v0; k < 3 * nv; k++) positions[k] += w[j] * dp[k];
                if (normals && mo->d_normals) {
                    const float *dn = mo->d_normals + (size_t)j * 3 * all;
                    for (size_t k = 3 * v0; k < 3 * nv; k++) normals[k] += w[j] * dn[k];
                }
            }
            if (w != wstack) free(w);
        }
    }
    if (m->skin) {
        const evr_skin *sk = m->skin;
        evr_m34 jstack[64], *jm = jstack;
        if (sk->num_joints > 64 && !(jm = malloc(sizeof *jm * (size_t)sk->num_joints))) return 0;
        joint_matrices(s, sk, t, jm);
        for (size_t v = v0; v < nv; v++) {
            evr_m34 b;
            memset(&b, 0, sizeof b);
            for (int k = 0; k < sk->influences; k++) {
                const size_t at = v * (size_t)sk->influences + (size_t)k;
                const float wk = sk->weights[at];
                if (wk == 0.0f) continue;
                const evr_m34 *j = &jm[sk->joints[at]];
                for (int r = 0; r < 3; r++)
                    for (int c = 0; c < 4; c++) b.m[r][c] += wk * j->m[r][c];
            }
            float *p = positions + 3 * v;
            const evr_v3 q = evr_m34_point(&b, evr_v3_make(p[0], p[1], p[2]));
            p[0] = q.x;
            p[1] = q.y;
            p[2] = q.z;
            if (normals) {
                float *nn = normals + 3 * v;
                const evr_v3 r = evr_m34_normal(&b, evr_v3_make(nn[0], nn[1], nn[2]));
                nn[0] = r.x;
                nn[1] = r.y;
                nn[2] = r.z;
            }
        }
        if (jm != jstack) free(jm);
    } else if (normals && m->morph) {
        for (size_t v = v0; v < nv; v++) {
            float *nn = normals + 3 * v;
            const evr_v3 r = evr_v3_norm(evr_v3_make(nn[0], nn[1], nn[2]));
            nn[0] = r.x;
            nn[1] = r.y;
            nn[2] = r.z;
        }
    }
    return 1;
}
