/* Bottom-level trees kept across runs (the CUDA backend's set-up of a big model): a group's tree,
 * as gpu_bvh_tree.c builds and flattens it, stored under a key of everything its build reads
 * (the group's triangles with their fields, the node layout, the build's quality, Embree's
 * version and the builder's own source), so that a later run of the same triangles loads it
 * instead of building it again. The same mesh in another file hits too.
 *
 * Files: DIR/bvh-KEY.evrbvh (KEY: 32 hex digits), written under a temporary name and renamed,
 * so a reader sees a whole file or none; several runs may share the folder. A file is checked
 * when read (its header, its size, a checksum of its content, every index in range): one that
 * fails is built again and replaced, with a note. Only trees of at least min_tris triangles
 * are kept; the folder's trees are held to max_bytes, the least recently used removed first. */
#ifndef EVR_CUDA_GPU_BVH_CACHE_H
#define EVR_CUDA_GPU_BVH_CACHE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* what the CUDA backend keeps: a smaller tree builds in a few milliseconds */
#define EVR_GPU_BVH_CACHE_MIN_TRIS 65536
#define EVR_GPU_BVH_CACHE_MAX_BYTES (4ull << 30)

typedef struct evr_gpu_bvh_cache {
    const char *dir;    /* the folder (made when first written); NULL: no cache */
    size_t min_tris;    /* trees of fewer triangles are built, not kept */
    uint64_t max_bytes; /* the folder's trees in all, at most (0: no bound) */
    /* what a build did with it */
    int loaded, stored; /* trees read from the folder, and written to it */
    char note[256];     /* the first file it could not read or write, and why; "" when none */
} evr_gpu_bvh_cache;

/* A cache in dir with the CUDA backend's bounds, nothing loaded or stored yet. */
void evr_gpu_bvh_cache_init(evr_gpu_bvh_cache *c, const char *dir);

#ifdef __cplusplus
}
#endif
#endif
