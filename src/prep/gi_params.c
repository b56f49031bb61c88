/* The run's GI settings, for both backends (see gi_params.h). */
#include "prep/gi_params.h"
#include "scene/scene.h"

#include <math.h>
#include <string.h>

void evr_gi_run_params(const evr_run_setup *setup, const evr_scene *s, uint32_t *photons,
                       evr_gather_params *gp, evr_photon_params *pp, int *margin, int *window)
{
    evr_v3 lo = s->bounds_min, hi = s->bounds_max;
    *photons =
        setup->photons ? setup->photons : (uint32_t)((size_t)setup->width * (size_t)setup->height);
    memset(gp, 0, sizeof *gp);
    gp->radius = setup->gather_radius;
    gp->max_photons = setup->gather_max;
    gp->max_window = setup->gather_window;
    gp->normal_cos = 0.7f;
    memset(pp, 0, sizeof *pp);
    pp->max_bounces = setup->gi_bounces;
    pp->f0 = 0.0f;
    pp->f1 = 1.0f;
    pp->seed = setup->seed;
    if (!(lo.x <= hi.x)) lo = hi = evr_v3_make(0.0f, 0.0f, 0.0f);
    pp->bounds.center = evr_v3_scale(evr_v3_add(lo, hi), 0.5f);
    pp->bounds.radius = 0.55f * evr_v3_len(evr_v3_sub(hi, lo)) + 1e-6f;
    *margin = setup->gather_window < 16 ? setup->gather_window : 16;
    /* the blurred estimate reads a pixel's cell and the eight around it (core/photon_blur.h) */
    *window = setup->gi_blur > 0.0f ? 1 : setup->gather_window + 1;
}

int evr_gi_photon_layers(int asked, uint32_t photons, int width, int height)
{
    const double pixels = (double)width * (double)height;
    double per_pixel = photons > 0u && pixels > 0.0 ? (double)photons / pixels : 1.0;
    if (asked > 0) return asked;
    if (per_pixel < 1.0) per_pixel = 1.0;
    return per_pixel >= 8.0 ? 64 : (int)ceil(8.0 * per_pixel);
}
