/* Cameras, perspective and orthographic (quirks (b) and (c) in import.c, and 3DS's in
 * docs/assimp-quirks.md), or one that frames the scene when the file has none. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/framing.h"
#include "scene/import_internal.h"

static int is_3ds(const evr_scene *s) { return strstr(s->format, "3DS") != NULL; }

/* v turned by angle a about the unit axis k (Rodrigues). */
static evr_v3 turn(evr_v3 v, evr_v3 k, float a)
{
    const float c = cosf(a), s = sinf(a);
    return evr_v3_add(evr_v3_add(evr_v3_scale(v, c), evr_v3_scale(evr_v3_cross(k, v), s)),
                      evr_v3_scale(k, evr_v3_dot(k, v) * (1.0f - c)));
}

/* 3DS is Z-up, but Assimp turns +Y about the view direction by the camera's bank angle for
 * mUp: the bank is read back from that and applied to +Z. */
static evr_v3 up_3ds(evr_v3 look, evr_v3 ai_up)
{
    const evr_v3 k = evr_v3_norm(look), y = evr_v3_make(0, 1, 0);
    const evr_v3 py = evr_v3_sub(y, evr_v3_scale(k, evr_v3_dot(k, y)));
    const evr_v3 pu = evr_v3_sub(ai_up, evr_v3_scale(k, evr_v3_dot(k, ai_up)));
    float bank = 0.0f;
    if (evr_v3_len(py) > 1e-4f && evr_v3_len(pu) > 1e-4f)
        bank = atan2f(evr_v3_dot(k, evr_v3_cross(py, pu)), evr_v3_dot(py, pu));
    return turn(evr_v3_make(0, 0, 1), k, bank);
}

/* The node named like the camera, or NULL. */
static const struct aiNode *camera_node(const struct aiNode *n, const char *name)
{
    if (!strcmp(n->mName.data, name)) return n;
    for (unsigned i = 0; i < n->mNumChildren; i++) {
        const struct aiNode *f = camera_node(n->mChildren[i], name);
        if (f) return f;
    }
    return NULL;
}

static void import_one(importer *im, const struct aiCamera *ac, unsigned i, evr_camera_desc *c)
{
    evr_scene *s = im->s;
    float h = ac->mHorizontalFOV;
    evr_import_copy_name(c->name, sizeof c->name, ac->mName.data);
    if (!c->name[0]) snprintf(c->name, sizeof c->name, "camera%u", i);
    c->node = evr_import_find_node(im, ac->mName.data);
    c->aspect = ac->mAspect > 0.0f ? ac->mAspect : 0.0f;
    c->znear = ac->mClipPlaneNear > 0.0f ? ac->mClipPlaneNear : 0.01f;
    c->yfov = (float)(EVR_PI_D / 4.0);
    if (ac->mOrthographicWidth > 0.0f) {
        /* glTF: mOrthographicWidth = xmag, mAspect = xmag / ymag */
        c->ortho = 1;
        c->ymag =
            ac->mAspect > 0.0f ? ac->mOrthographicWidth / ac->mAspect : ac->mOrthographicWidth;
    } else if (!(h > 0.0f)) {
        /* no angle: 45 degrees */
    } else if (im->gltf) {
        /* quirk (b): Assimp stored yfov * aspect */
        c->yfov = ac->mAspect > 0.0f ? h / ac->mAspect : h;
    } else {
        /* the full horizontal angle, as Assimp's importers store it: 3DS's is the lens's focal
         * length in mm taken for degrees, of a 36 mm wide film (3ds Max's aperture) */
        if (is_3ds(s)) h = 2.0f * atanf(18.0f / (h * (float)(180.0 / EVR_PI_D)));
        if (ac->mAspect > 0.0f) {
            c->yfov = 2.0f * atanf(tanf(0.5f * h) / ac->mAspect);
        } else { /* the image's aspect gives yfov (evr_camera_yfov); a square one here */
            c->xfov = h;
            c->yfov = h;
        }
    }
    if (im->gltf) {
        /* quirk (c): mPosition repeats the node's translation; glTF cameras sit at their
         * node's origin looking along -Z with +Y up */
        c->local = evr_m34_identity();
        return;
    }
    evr_v3 pos = evr_v3_make(ac->mPosition.x, ac->mPosition.y, ac->mPosition.z);
    evr_v3 look = evr_v3_make(ac->mLookAt.x, ac->mLookAt.y, ac->mLookAt.z);
    evr_v3 up = evr_v3_make(ac->mUp.x, ac->mUp.y, ac->mUp.z);
    if (is_3ds(s)) {
        /* with a keyframer section the camera's node holds its position too: quirk (c) again */
        const struct aiNode *n = camera_node(im->ai->mRootNode, ac->mName.data);
        if (n && evr_v3_len(pos) > 0.0f &&
            evr_v3_len(evr_v3_sub(pos, evr_v3_make(n->mTransformation.a4, n->mTransformation.b4,
                                                   n->mTransformation.c4))) <=
                1e-5f * evr_v3_len(pos))
            pos = evr_v3_make(0, 0, 0);
        up = up_3ds(look, up);
    }
    c->local = evr_frame_look_along(pos, look, up);
}

/* The automatic camera: the scene over its whole animation seen from the direction that sees
 * the most of it (framing.h), at 45 degrees, for a square image (a render frames it again for
 * its image's shape, evr_camera_rig_init). */
static void automatic(evr_scene *s, evr_camera_desc *c)
{
    evr_v3 lo, hi;
    float dist;
    const float fov = (float)(EVR_PI_D / 4.0);
    evr_frame_swept_bounds(s, s->anim_start, s->anim_end, &lo, &hi);
    const float r = 0.5f * evr_v3_len(evr_v3_sub(hi, lo));
    strcpy(c->name, "automatic");
    c->node = -1;
    c->yfov = fov;
    c->aspect = 0.0f;
    c->local = evr_frame_box(lo, hi, evr_frame_direction(s, s->anim_start), fov, 1.0f, 0, &dist);
    c->znear = fmaxf(1e-4f * dist, 0.01f * (dist - (r > 0.0f ? r : 0.0f)));
    if (!(c->znear > 0.0f)) c->znear = 0.01f;
    c->automatic = 1;
}

evr_status evr_import_cameras(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    s->cameras = calloc((size_t)ai->mNumCameras + 1, sizeof *s->cameras);
    if (!s->cameras)
        return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading cameras");
    for (i = 0; i < ai->mNumCameras; i++)
        import_one(im, ai->mCameras[i], i, &s->cameras[s->num_cameras++]);
    if (s->num_cameras == 0) automatic(s, &s->cameras[s->num_cameras++]);
    return EVR_OK;
}
