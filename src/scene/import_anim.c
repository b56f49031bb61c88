/* Node animation curves of the played clips (import_clips.c) in seconds (quirk (a) in
 * import.c), with what the glTF JSON says of each channel (quirks (d), (e) and STEP):
 * synthesized and rest-only curves dropped. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/import_internal.h"

/* 1 when every key of the curve holds the node's rest value (such a curve changes nothing). */
static int curve_is_rest(const evr_curve *c, const float *rest, int dim)
{
    int k, j;
    for (k = 0; k < c->num_keys; k++) {
        const float *v = c->values + (size_t)k * (size_t)dim;
        if (dim == 4) {
            float d = v[0] * rest[0] + v[1] * rest[1] + v[2] * rest[2] + v[3] * rest[3];
            if (fabsf(d) < 1.0f - 1e-7f) return 0;
        } else {
            for (j = 0; j < dim; j++)
                if (fabsf(v[j] - rest[j]) > 1e-6f * fmaxf(1.0f, fabsf(rest[j]))) return 0;
        }
    }
    return 1;
}

void evr_import_curve_free(evr_curve *c)
{
    free(c->times);
    free(c->values);
    memset(c, 0, sizeof *c);
}

void evr_import_curve_sort(evr_curve *c, int dim)
{
    /* insertion sort by adjacent swaps (keys are nearly always sorted already) */
    int i, j, d;
    for (i = 1; i < c->num_keys; i++)
        for (j = i; j > 0 && c->times[j - 1] > c->times[j]; j--) {
            float *a = c->values + (size_t)(j - 1) * (size_t)dim, *b = a + dim;
            double t = c->times[j];
            c->times[j] = c->times[j - 1];
            c->times[j - 1] = t;
            for (d = 0; d < dim; d++) {
                float v = a[d];
                a[d] = b[d];
                b[d] = v;
            }
        }
}

/* Copies one kind of keys (dim 3: aiVectorKey, 4: aiQuatKey) into a curve in seconds. */
static int make_curve(evr_curve *c, const void *keys, unsigned nkeys, int dim, double tps)
{
    unsigned k;
    int sorted = 1;
    c->times = malloc((size_t)nkeys * sizeof(double));
    c->values = malloc((size_t)nkeys * (size_t)dim * sizeof(float));
    if (!c->times || !c->values) {
        evr_import_curve_free(c);
        return 0;
    }
    c->num_keys = (int)nkeys;
    for (k = 0; k < nkeys; k++) {
        float *v = c->values + (size_t)k * (size_t)dim;
        if (dim == 3) {
            const struct aiVectorKey *key = (const struct aiVectorKey *)keys + k;
            c->times[k] = key->mTime / tps;
            v[0] = key->mValue.x;
            v[1] = key->mValue.y;
            v[2] = key->mValue.z;
        } else {
            const struct aiQuatKey *key = (const struct aiQuatKey *)keys + k;
            evr_quat q = evr_quat_normalize(
                evr_quat_make(key->mValue.w, key->mValue.x, key->mValue.y, key->mValue.z));
            c->times[k] = key->mTime / tps;
            v[0] = q.w;
            v[1] = q.x;
            v[2] = q.y;
            v[3] = q.z;
        }
        if (k && c->times[k] < c->times[k - 1]) sorted = 0;
    }
    if (!sorted) evr_import_curve_sort(c, dim);
    return 1;
}

double evr_import_ticks_per_second(const struct aiAnimation *an)
{
    /* quirk (a): glTF keys are in milliseconds, mTicksPerSecond = 1000 */
    return an->mTicksPerSecond > 0.0 ? an->mTicksPerSecond : 25.0;
}

int evr_import_channel_interp(const importer *im, unsigned a, const char *node, int path)
{
    int side_ok = im->have_side && im->side.num_anims == (int)im->ai->mNumAnimations;
    if (!im->have_side) return GL_LINEAR;
    /* quirk (e): keys of properties no glTF channel animates are synthesized */
    return evr_gltf_side_interp(&im->side, side_ok ? (int)a : -1, node, path);
}

evr_status evr_import_animation(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned a, ch;
    int i, any = 0;
    double t_min = INFINITY, t_max = -INFINITY;

    for (a = 0; a < ai->mNumAnimations; a++) {
        const struct aiAnimation *an = ai->mAnimations[a];
        double tps = evr_import_ticks_per_second(an);
        if (!evr_import_clip_played(im, a)) continue;
        if (an->mNumMeshChannels) /* vertex animation by swapping meshes (MD2, MD3, ...) */
            evr_import_warn(im,
                            "clip '%s': its %u mesh channel%s (meshes swapped per key) %s not "
                            "rendered",
                            an->mName.data, an->mNumMeshChannels,
                            an->mNumMeshChannels == 1 ? "" : "s",
                            an->mNumMeshChannels == 1 ? "is" : "are");
        for (ch = 0; ch < an->mNumChannels; ch++) {
            const struct aiNodeAnim *na = an->mChannels[ch];
            int ni = evr_import_find_node(im, na->mNodeName.data), kind;
            evr_node *n;
            if (ni < 0) {
                evr_import_warn(im, "clip '%s': a channel animates '%s', which no node is named",
                                an->mName.data, na->mNodeName.data);
                continue;
            }
            n = &s->nodes[ni];
            for (kind = 0; kind < 3; kind++) {
                evr_curve *c = kind == PATH_T   ? &n->t_curve
                               : kind == PATH_R ? &n->r_curve
                                                : &n->s_curve;
                unsigned nk = kind == PATH_T   ? na->mNumPositionKeys
                              : kind == PATH_R ? na->mNumRotationKeys
                                               : na->mNumScalingKeys;
                const void *keys = kind == PATH_T   ? (const void *)na->mPositionKeys
                                   : kind == PATH_R ? (const void *)na->mRotationKeys
                                                    : (const void *)na->mScalingKeys;
                int interp;
                float rest[4];
                if (nk == 0 || !keys || c->num_keys > 0) continue; /* first animation wins */
                interp = evr_import_channel_interp(im, a, na->mNodeName.data, kind);
                if (interp < 0) continue; /* synthesized */
                if (!make_curve(c, keys, nk, kind == PATH_R ? 4 : 3, tps))
                    return evr_import_fail(im->err, EVR_ERR_NOMEM,
                                           "out of memory reading animations");
                /* STEP from the JSON; CUBICSPLINE values (quirk (d)) are interpolated linearly */
                c->interp = interp == GL_STEP ? EVR_INTERP_STEP : EVR_INTERP_LINEAR;
                if (kind == PATH_T) {
                    rest[0] = n->translation.x;
                    rest[1] = n->translation.y;
                    rest[2] = n->translation.z;
                } else if (kind == PATH_S) {
                    rest[0] = n->scale.x;
                    rest[1] = n->scale.y;
                    rest[2] = n->scale.z;
                } else {
                    rest[0] = n->rotation.w;
                    rest[1] = n->rotation.x;
                    rest[2] = n->rotation.y;
                    rest[3] = n->rotation.z;
                }
                if (curve_is_rest(c, rest, kind == PATH_R ? 4 : 3)) evr_import_curve_free(c);
            }
        }
    }
    for (i = 0; i < s->num_nodes; i++) {
        evr_node *n = &s->nodes[i];
        const evr_curve *cv[3];
        int k;
        cv[0] = &n->t_curve;
        cv[1] = &n->r_curve;
        cv[2] = &n->s_curve;
        for (k = 0; k < 3; k++) {
            if (cv[k]->num_keys <= 0) continue;
            n->animated = 1;
            any = 1;
            if (cv[k]->times[0] < t_min) t_min = cv[k]->times[0];
            if (cv[k]->times[cv[k]->num_keys - 1] > t_max)
                t_max = cv[k]->times[cv[k]->num_keys - 1];
        }
    }
    /* The played clips run to their last key, also where their last curves were dropped (they
     * hold the rest value): a clip as long as `evray info` says it is. */
    for (a = 0; a < (unsigned)s->num_animations && s->clips; a++) {
        const evr_clip *c = &s->clips[a];
        if (!c->played || c->num_nodes == 0) continue;
        if (c->start < t_min) t_min = c->start;
        if (c->end > t_max) t_max = c->end;
        any = 1;
    }
    if (any) {
        s->anim_start = t_min;
        s->anim_end = t_max;
    }
    /* glTF has no frame rate. FBX and BVH store keys in frames (ticks per second = frames per
     * second); Collada uses 1 tick per second, which says nothing. The first played clip's. */
    for (a = 0; a < ai->mNumAnimations && !evr_import_clip_played(im, a); a++) continue;
    if (!im->gltf && a < ai->mNumAnimations && ai->mAnimations[a]->mTicksPerSecond >= 10.0 &&
        ai->mAnimations[a]->mTicksPerSecond <= 240.0)
        s->frame_rate = ai->mAnimations[a]->mTicksPerSecond;
    return EVR_OK;
}
