/* Every number of the imported scene checked, whatever the format (a glTF was checked before
 * Assimp read it, import_gltf_validate.c; the other formats come only through Assimp, which
 * passes on whatever the file says). A NaN vertex or key, a zero quaternion, a camera without a
 * field of view or a light of negative intensity does not fail anywhere later: it silently
 * makes no events (a zero quaternion turned an object's 18,351 events into 0), so each is one
 * error line naming the element. */
#include <math.h>
#include <stdio.h>

#include "scene/import_internal.h"

#define PI_F 3.14159265f

/* Index of the first of n floats that is not finite, or -1. */
static long first_bad(const float *v, size_t n)
{
    size_t i;
    for (i = 0; v && i < n; i++)
        if (!isfinite(v[i])) return (long)i;
    return -1;
}

static int quat_ok(float w, float x, float y, float z)
{
    float n = w * w + x * x + y * y + z * z;
    return isfinite(n) && n > 1e-12f;
}

static evr_status bad(importer *im, const char *fmt, const char *name, long at)
{
    char what[160];
    snprintf(what, sizeof what, fmt, name, at);
    return evr_import_fail(im->err, EVR_ERR_FORMAT, "'%s': %s", im->s->source, what);
}

static evr_status bad_name(importer *im, const char *fmt, const char *name)
{
    char what[160];
    snprintf(what, sizeof what, fmt, name);
    return evr_import_fail(im->err, EVR_ERR_FORMAT, "'%s': %s", im->s->source, what);
}

static evr_status check_meshes(importer *im)
{
    const evr_scene *s = im->s;
    int i;
    long k;
    for (i = 0; i < s->num_meshes; i++) {
        const evr_mesh *m = &s->meshes[i];
        size_t nv = m->num_vertices;
        if ((k = first_bad(m->positions, 3 * nv)) >= 0)
            return bad(im, "mesh '%s': vertex %ld is not finite", m->name, k / 3);
        if ((k = first_bad(m->normals, 3 * nv)) >= 0)
            return bad(im, "mesh '%s': the normal of vertex %ld is not finite", m->name, k / 3);
        if ((k = first_bad(m->uvs, 2 * nv)) >= 0)
            return bad(im, "mesh '%s': the uv of vertex %ld is not finite", m->name, k / 2);
        if ((k = first_bad(m->tangents, 4 * nv)) >= 0)
            return bad(im, "mesh '%s': the tangent of vertex %ld is not finite", m->name, k / 4);
        if (m->morph &&
            (k = first_bad(m->morph->d_positions, (size_t)m->morph->num_targets * 3 * nv)) >= 0)
            return bad(im,
                       "mesh '%s': a morph target moves vertex %ld by a number that is not finite",
                       m->name, (long)((size_t)k / 3 % (nv ? nv : 1)));
        if (m->skin &&
            (k = first_bad(m->skin->inverse_bind ? &m->skin->inverse_bind[0].m[0][0] : NULL,
                           (size_t)m->skin->num_joints * 12)) >= 0)
            return bad(im, "mesh '%s': inverse bind matrix %ld is not finite", m->name, k / 12);
    }
    return EVR_OK;
}

/* A curve's times and values finite; rotation keys (dim 4) not zero quaternions. */
static evr_status check_curve(importer *im, const evr_node *n, const evr_curve *c, int dim,
                              const char *what)
{
    char fmt[96];
    int k;
    long b;
    for (k = 0; k < c->num_keys; k++)
        if (!isfinite(c->times[k])) {
            snprintf(fmt, sizeof fmt, "node '%%s': %s key %%ld has a time that is not finite",
                     what);
            return bad(im, fmt, n->name, k);
        }
    if ((b = first_bad(c->values, (size_t)c->num_keys * (size_t)dim)) >= 0) {
        snprintf(fmt, sizeof fmt, "node '%%s': %s key %%ld is not finite", what);
        return bad(im, fmt, n->name, b / dim);
    }
    for (k = 0; dim == 4 && k < c->num_keys; k++) {
        const float *q = c->values + 4 * (size_t)k;
        if (!quat_ok(q[0], q[1], q[2], q[3]))
            return bad(im, "node '%s': rotation key %ld is the zero quaternion", n->name, k);
    }
    return EVR_OK;
}

static evr_status check_nodes(importer *im)
{
    const evr_scene *s = im->s;
    evr_status st;
    int i;
    for (i = 0; i < s->num_nodes; i++) {
        const evr_node *n = &s->nodes[i];
        const float trs[10] = {n->translation.x, n->translation.y, n->translation.z, n->scale.x,
                               n->scale.y,       n->scale.z,       n->rotation.w,    n->rotation.x,
                               n->rotation.y,    n->rotation.z};
        if (first_bad(trs, 10) >= 0 || first_bad(&n->rest_matrix.m[0][0], 12) >= 0)
            return bad_name(im, "node '%s': its transform is not finite", n->name);
        if (!quat_ok(n->rotation.w, n->rotation.x, n->rotation.y, n->rotation.z))
            return bad_name(im, "node '%s': its rotation is the zero quaternion", n->name);
        if (first_bad(n->weights, (size_t)n->num_weights) >= 0)
            return bad_name(im, "node '%s': a morph weight is not finite", n->name);
        if ((st = check_curve(im, n, &n->t_curve, 3, "translation")) != EVR_OK ||
            (st = check_curve(im, n, &n->r_curve, 4, "rotation")) != EVR_OK ||
            (st = check_curve(im, n, &n->s_curve, 3, "scale")) != EVR_OK ||
            (st = check_curve(im, n, &n->w_curve, n->num_weights, "morph weight")) != EVR_OK)
            return st;
    }
    return EVR_OK;
}

static evr_status check_cameras_lights(importer *im)
{
    const evr_scene *s = im->s;
    int i;
    for (i = 0; i < s->num_cameras; i++) {
        const evr_camera_desc *c = &s->cameras[i];
        if (c->automatic) continue;
        if (!(c->yfov > 0 && c->yfov < PI_F))
            return bad_name(im, "camera '%s': its field of view must be between 0 and pi radians",
                            c->name);
        if (!(c->znear > 0 && isfinite(c->znear)))
            return bad_name(im, "camera '%s': its near plane must be a distance > 0", c->name);
        if (!(c->aspect >= 0 && isfinite(c->aspect)) || first_bad(&c->local.m[0][0], 12) >= 0)
            return bad_name(im, "camera '%s': its aspect ratio or pose is not finite", c->name);
    }
    for (i = 0; i < s->num_lights; i++) {
        const evr_light *l = &s->lights[i];
        const float v[11] = {l->color[0],    l->color[1],   l->color[2],    l->position.x,
                             l->position.y,  l->position.z, l->direction.x, l->direction.y,
                             l->direction.z, l->inner_cone, l->outer_cone};
        if (first_bad(v, 11) >= 0 || !isfinite(l->radius))
            return bad_name(im, "light '%s': a parameter is not finite", l->name);
        if (l->color[0] < 0 || l->color[1] < 0 || l->color[2] < 0)
            return bad_name(im, "light '%s': its intensity is negative", l->name);
    }
    return EVR_OK;
}

evr_status evr_import_check_numbers(importer *im)
{
    evr_status st;
    if ((st = check_meshes(im)) != EVR_OK || (st = check_nodes(im)) != EVR_OK) return st;
    return check_cameras_lights(im);
}
