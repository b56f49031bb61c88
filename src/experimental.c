/* The parts of evray_experimental.h that are views of internals: the clock, scene figures, the
 * renderer's luminance and evray still's result. */
#include "evray_experimental.h"
#include "core/shading.h"
#include "host_clock.h"
#include "scene/scene.h"
#include "cpu/still.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

double evr_seconds(void) { return evr_host_seconds(); }

float evr_rgb_luminance(const float rgb[3]) { return evr_luminance(rgb[0], rgb[1], rgb[2]); }

int evr_scene_num_instances(const evr_scene *s) { return s->num_instances; }

const char *evr_scene_instance_node(const evr_scene *s, int i)
{
    return s->nodes[s->instances[i].node].name;
}

const char *evr_scene_instance_mesh(const evr_scene *s, int i)
{
    return s->meshes[s->instances[i].mesh].name;
}

void evr_scene_triangles(const evr_scene *s, uint64_t *mesh_triangles, uint64_t *scene_triangles)
{
    int k;
    uint64_t m = 0, t = 0;
    for (k = 0; k < s->num_meshes; k++) m += (uint64_t)s->meshes[k].num_triangles;
    for (k = 0; k < s->num_instances; k++)
        t += (uint64_t)s->meshes[s->instances[k].mesh].num_triangles;
    *mesh_triangles = m;
    *scene_triangles = t;
}

evr_status evr_still_image_render(const evr_scene *s, const evr_still_params *p,
                                  evr_still_image *out, evr_error *err)
{
    evr_still_result *r = malloc(sizeof *r);
    evr_status st;
    memset(out, 0, sizeof *out);
    if (!r) {
        snprintf(err->msg, sizeof err->msg, "out of memory");
        return EVR_ERR_NOMEM;
    }
    if ((st = evr_still_render(s, p, r, err)) != EVR_OK) {
        free(r);
        return st;
    }
    out->width = r->width;
    out->height = r->height;
    out->rgb = r->rgb;
    out->direct = r->direct;
    out->instance = r->instance;
    out->photon_paths = r->photon.paths;
    out->photons_stayed = r->photon.stored_photons;
    out->photons_visible = r->photon.visible;
    out->photons_inserted = r->photon.inserted;
    out->photon_collisions = r->photon.collisions;
    out->gather_radius = r->gather_radius;
    out->photon_layers = r->photon_layers;
    out->photons_per_estimate = r->photons_per_estimate;
    out->seconds_setup = r->seconds_setup;
    out->seconds_photons = r->seconds_photons;
    out->seconds_shading = r->seconds_shading;
    out->threads = r->threads;
    out->result = r;
    return EVR_OK;
}

void evr_still_image_free(evr_still_image *im)
{
    if (im->result) {
        evr_still_result_free(im->result);
        free(im->result);
    }
    memset(im, 0, sizeof *im);
}
