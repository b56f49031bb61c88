/* Perspective cameras (quirks (b) and (c) in import.c), or one that frames the scene when the
 * file has none. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/import_internal.h"

/* Camera pose from a position, a viewing direction and an up vector: -Z along look, +Y up. */
static evr_m34 look_matrix(evr_v3 pos, evr_v3 look, evr_v3 up)
{
    evr_m34 m;
    evr_v3 z = evr_v3_norm(evr_v3_scale(look, -1.0f)), x, y;
    if (evr_v3_len(z) == 0.0f) z = evr_v3_make(0, 0, 1);
    x = evr_v3_cross(up, z);
    if (evr_v3_len(x) < 1e-6f)
        x = evr_v3_cross(fabsf(z.y) < 0.9f ? evr_v3_make(0, 1, 0) : evr_v3_make(1, 0, 0), z);
    x = evr_v3_norm(x);
    y = evr_v3_cross(z, x);
    m.m[0][0] = x.x;
    m.m[0][1] = y.x;
    m.m[0][2] = z.x;
    m.m[0][3] = pos.x;
    m.m[1][0] = x.y;
    m.m[1][1] = y.y;
    m.m[1][2] = z.y;
    m.m[1][3] = pos.y;
    m.m[2][0] = x.z;
    m.m[2][1] = y.z;
    m.m[2][2] = z.z;
    m.m[2][3] = pos.z;
    return m;
}

evr_status evr_import_cameras(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    s->cameras = calloc((size_t)ai->mNumCameras + 1, sizeof *s->cameras);
    if (!s->cameras)
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading cameras");
    for (i = 0; i < ai->mNumCameras; i++) {
        const struct aiCamera *ac = ai->mCameras[i];
        evr_camera_desc *c = &s->cameras[s->num_cameras++];
        float h = ac->mHorizontalFOV;
        evr_import_copy_name(c->name, sizeof c->name, ac->mName.data);
        if (!c->name[0]) snprintf(c->name, sizeof c->name, "camera%u", i);
        c->node = evr_import_find_node(im, ac->mName.data);
        c->aspect = ac->mAspect > 0.0f ? ac->mAspect : 0.0f;
        c->znear = ac->mClipPlaneNear > 0.0f ? ac->mClipPlaneNear : 0.01f;
        if (!(h > 0.0f)) {
            c->yfov = (float)(EVR_PI_D / 4.0); /* orthographic: not supported, 45 degrees */
        } else if (im->gltf) {
            /* quirk (b): Assimp stored yfov * aspect */
            c->yfov = ac->mAspect > 0.0f ? h / ac->mAspect : h;
        } else {
            /* the full horizontal angle, as Assimp's importers store it */
            c->yfov = ac->mAspect > 0.0f ? 2.0f * atanf(tanf(0.5f * h) / ac->mAspect) : h;
        }
        if (im->gltf) {
            /* quirk (c): mPosition repeats the node's translation; glTF cameras sit at their
             * node's origin looking along -Z with +Y up */
            c->local = evr_m34_identity();
        } else {
            c->local = look_matrix(evr_v3_make(ac->mPosition.x, ac->mPosition.y, ac->mPosition.z),
                                   evr_v3_make(ac->mLookAt.x, ac->mLookAt.y, ac->mLookAt.z),
                                   evr_v3_make(ac->mUp.x, ac->mUp.y, ac->mUp.z));
        }
    }
    if (s->num_cameras == 0) {
        /* Frame the rest-pose bounds: look along -Z at the centre from where the bounding
         * sphere fills a 45-degree vertical field of view. */
        evr_camera_desc *c = &s->cameras[s->num_cameras++];
        evr_v3 centre = evr_v3_scale(evr_v3_add(s->bounds_min, s->bounds_max), 0.5f);
        float r = 0.5f * evr_v3_len(evr_v3_sub(s->bounds_max, s->bounds_min));
        float fov = (float)(EVR_PI_D / 4.0), dist;
        if (!(r > 0.0f)) r = 1.0f;
        dist = r / sinf(0.5f * fov);
        strcpy(c->name, "automatic");
        c->node = -1;
        c->yfov = fov;
        c->aspect = 0.0f;
        c->znear = fmaxf(1e-4f * dist, 0.01f * (dist - r));
        c->local = look_matrix(evr_v3_add(centre, evr_v3_make(0, 0, dist)), evr_v3_make(0, 0, -1),
                               evr_v3_make(0, 1, 0));
        c->automatic = 1;
    }
    return EVR_OK;
}
