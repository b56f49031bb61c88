/* Punctual lights (point, spot, directional), or a headlight riding with the first camera when
 * the file has none. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/import_internal.h"

evr_status evr_import_lights(importer *im)
{
    const struct aiScene *ai = im->ai;
    evr_scene *s = im->s;
    unsigned i;
    s->lights = calloc((size_t)ai->mNumLights + 1, sizeof *s->lights);
    if (!s->lights) return evr_import_fail(im->err, EVR_ERR_NOMEM, "out of memory reading lights");
    for (i = 0; i < ai->mNumLights; i++) {
        const struct aiLight *al = ai->mLights[i];
        evr_light *l = &s->lights[s->num_lights];
        evr_v3 dir = evr_v3_make(al->mDirection.x, al->mDirection.y, al->mDirection.z);
        if (al->mType == aiLightSource_POINT) l->type = EVR_LIGHT_POINT;
        else if (al->mType == aiLightSource_SPOT) l->type = EVR_LIGHT_SPOT;
        else if (al->mType == aiLightSource_DIRECTIONAL) l->type = EVR_LIGHT_DIRECTIONAL;
        else { /* ambient and area lights: not punctual (the config has an ambient term) */
            evr_import_warn(im,
                            "light '%s' is an %s light, which evray does not render (--ambient "
                            "sets an ambient term)",
                            al->mName.data,
                            al->mType == aiLightSource_AMBIENT ? "ambient" : "area");
            continue;
        }
        s->num_lights++;
        evr_import_copy_name(l->name, sizeof l->name, al->mName.data);
        if (!l->name[0]) snprintf(l->name, sizeof l->name, "light%u", i);
        l->node = evr_import_find_node(im, al->mName.data);
        /* glTF: colour * intensity already */
        l->color[0] = al->mColorDiffuse.r;
        l->color[1] = al->mColorDiffuse.g;
        l->color[2] = al->mColorDiffuse.b;
        l->position = evr_v3_make(al->mPosition.x, al->mPosition.y, al->mPosition.z);
        l->direction = evr_v3_len(dir) > 0.0f ? evr_v3_norm(dir) : evr_v3_make(0, 0, -1);
        /* Assimp keeps glTF's light order (aiLight i is KHR_lights_punctual light i) */
        if (im->have_side && (int)i < im->side.num_lights && l->type != EVR_LIGHT_DIRECTIONAL)
            l->radius = im->side.light_radius[i];
        if (l->type == EVR_LIGHT_SPOT) {
            float k = im->gltf ? 1.0f : 0.5f; /* glTF gives half angles, the others full ones */
            l->inner_cone = al->mAngleInnerCone * k;
            l->outer_cone = al->mAngleOuterCone * k;
            if (!(l->outer_cone > 0.0f) || l->outer_cone > (float)(EVR_PI_D / 2.0))
                l->outer_cone = (float)(EVR_PI_D / 4.0);
            if (!(l->inner_cone >= 0.0f) || l->inner_cone > l->outer_cone)
                l->inner_cone = l->outer_cone;
        } else {
            l->inner_cone = l->outer_cone = (float)EVR_PI_D;
        }
    }
    if (s->num_lights == 0) {
        /* A headlight: directional, riding with the first camera, shining along its view
         * direction tilted to come from above-left; illuminance pi makes a white Lambertian
         * surface facing it radiance 1. */
        const evr_camera_desc *c = &s->cameras[0];
        evr_light *l = &s->lights[s->num_lights++];
        evr_v3 d = evr_v3_norm(evr_v3_make(0.25f, -0.25f, -1.0f)); /* camera space */
        strcpy(l->name, "headlight");
        l->type = EVR_LIGHT_DIRECTIONAL;
        l->node = c->node;
        l->color[0] = l->color[1] = l->color[2] = (float)EVR_PI_D;
        l->position = evr_m34_point(&c->local, evr_v3_make(0, 0, 0));
        l->direction = evr_v3_norm(evr_m34_vector(&c->local, d));
        l->inner_cone = l->outer_cone = (float)EVR_PI_D;
        s->default_light = 1;
    }
    return EVR_OK;
}
