/* The run's global-illumination settings, made once from the run setup for either backend. */
#ifndef EVR_PREP_GI_PARAMS_H
#define EVR_PREP_GI_PARAMS_H

#include <stdint.h>
#include "backend.h"
#include "core/photon.h"

/* The run's GI settings, the same for the CPU and CUDA backends: photons per pass (0 asked: one
 * per pixel), gather parameters, pass parameters (photons spread over the segment, the same
 * times every segment; directional lights emit over a disk round the scene's rest bounds, a
 * little larger), the buffer's guard band and the cells around a pixel a gather may read. */
void evr_gi_run_params(const evr_run_setup *setup, const evr_scene *s, uint32_t *photons,
                       evr_gather_params *gp, evr_photon_params *pp, int *margin, int *window);

/* The photon buffer's layers: `asked` (config's photon_layers) when set, otherwise 8 for each
 * photon per pixel the pass traces (one per pixel without `photons`), at most 64; a pixel the
 * light favours receives several times the mean, and a full pixel drops what comes later. */
int evr_gi_photon_layers(int asked, uint32_t photons, int width, int height);

#endif
