/* Bottom-level trees kept across runs (gpu_bvh_cache.h): keys, files, checks. */
#include "cuda/gpu_bvh_cache.h"
#include "cuda/gpu_bvh_code.h" /* generated: EVR_GPU_BVH_CODE, a hash of the builder's sources */
#include "cuda/gpu_bvh_internal.h"
#include "io/file_read.h"
#include "io/mkdir_p.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <xxhash.h>

/* a file: this header, then the tree's nodes (child and item indices from the tree's first node
 * and item) and its items */
#define MAGIC "evrBVH\r\n"
#define FORMAT 1
typedef struct {
    char magic[8];
    uint32_t format, layout;
    uint8_t key[16];
    uint32_t num_nodes, num_items;
    uint32_t node_bytes, item_bytes; /* sizeof a node and an item: a build of other structs */
    uint64_t checksum;               /* XXH3-64 of everything after the header */
} file_header;

void evr_gpu_bvh_cache_init(evr_gpu_bvh_cache *c, const char *dir)
{
    memset(c, 0, sizeof *c);
    c->dir = dir;
    c->min_tris = EVR_GPU_BVH_CACHE_MIN_TRIS;
    c->max_bytes = EVR_GPU_BVH_CACHE_MAX_BYTES;
}

void evr_gpu_cache_key(const flat_ctx *c, size_t n, int high, unsigned max_leaf, uint8_t key[16])
{
    XXH3_state_t *st = XXH3_createState();
    const uint32_t settings[4] = {(uint32_t)c->layout, (uint32_t)high, max_leaf,
                                  (uint32_t)RTC_VERSION};
    const uint64_t count = n;
    XXH128_hash_t h;
    XXH128_canonical_t out;
    if (!st) { /* no memory for 600 bytes: a key no file has */
        memset(key, 0xff, 16);
        return;
    }
    XXH3_128bits_reset(st);
    XXH3_128bits_update(st, EVR_GPU_BVH_CODE, sizeof EVR_GPU_BVH_CODE);
    XXH3_128bits_update(st, settings, sizeof settings);
    XXH3_128bits_update(st, &count, sizeof count);
    XXH3_128bits_update(st, c->tri9, 9 * sizeof(float) * n);
    XXH3_128bits_update(st, c->tri_prim, sizeof(uint32_t) * n);
    XXH3_128bits_update(st, c->tri_inst, sizeof(int32_t) * n);
    XXH3_128bits_update(st, c->tri_filter, sizeof(uint32_t) * n);
    h = XXH3_128bits_digest(st);
    XXH3_freeState(st);
    XXH128_canonicalFromHash(&out, h);
    memcpy(key, out.digest, 16);
}

static void key_path(const evr_gpu_bvh_cache *cache, const uint8_t key[16], char *buf, size_t n)
{
    char hex[33];
    for (int i = 0; i < 16; i++) snprintf(hex + 2 * i, 3, "%02x", key[i]);
    snprintf(buf, n, "%s/bvh-%s.evrbvh", cache->dir, hex);
}

static void note(evr_gpu_bvh_cache *cache, const char *what, const char *path, const char *why)
{
    if (cache->note[0]) return; /* the first says enough */
    snprintf(cache->note, sizeof cache->note, "BVH cache: %s %s: %s", what, path, why);
}

/* 1 when every child and item index of the tree (nodes and items from 0, children after their
 * parent) is in range: what the traversal and evr_gpu_tree_stack_need rely on. */
static int tree_valid(int layout, const void *nodes, uint32_t nn, uint32_t ni)
{
    for (uint32_t i = 0; i < nn; i++) {
        if (layout == EVR_GPU_LAYOUT_CW8) {
            const evr_gpu_node8 *nd = (const evr_gpu_node8 *)nodes + i;
            uint32_t inner = 0;
            for (int s = 0; s < 8; s++) {
                const unsigned m = nd->meta[s];
                if (m == 0) continue;
                if (nd->imask >> s & 1u) {
                    if (m != (0x20u | (24u + (unsigned)s))) return 0;
                    inner++;
                } else {
                    const unsigned bits = m >> 5, off = m & 31u;
                    const unsigned count = bits == 1 ? 1 : bits == 3 ? 2 : bits == 7 ? 3 : 0;
                    if (!count || (uint64_t)nd->item_base + off + count > ni) return 0;
                }
            }
            if (inner && (nd->child_base <= i || (uint64_t)nd->child_base + inner > nn)) return 0;
        } else {
            const evr_gpu_node4 *nd = (const evr_gpu_node4 *)nodes + i;
            for (int j = 0; j < 4; j++) {
                if (nd->child[j] < 0) continue;
                if (nd->count[j] == 0) {
                    if ((uint32_t)nd->child[j] <= i || (uint32_t)nd->child[j] >= nn) return 0;
                } else if ((uint64_t)(uint32_t)nd->child[j] + nd->count[j] > ni) {
                    return 0;
                }
            }
        }
    }
    return 1;
}

int evr_gpu_cache_load(evr_gpu_bvh_cache *cache, const uint8_t key[16], flat_ctx *c)
{
    char path[4096];
    file_header h;
    FILE *f;
    struct stat sb;
    const size_t node_bytes = evr_gpu_node_size(c->layout);
    void *nodes;
    const char *bad = NULL, *why = NULL;
    key_path(cache, key, path, sizeof path);
    errno = 0;
    f = evr_fopen_regular(path, &why); /* a FIFO in its place would block the read */
    if (!f) {
        /* none yet, or no folder (which writing it says) */
        if (errno != ENOENT && errno != ENOTDIR) note(cache, "cannot read", path, why);
        return 0;
    }
    if (fread(&h, sizeof h, 1, f) != 1 || fstat(fileno(f), &sb) != 0) {
        bad = "shorter than its header";
    } else if (memcmp(h.magic, MAGIC, 8) != 0 || h.format != FORMAT ||
               h.layout != (uint32_t)c->layout || memcmp(h.key, key, 16) != 0 ||
               h.node_bytes != node_bytes || h.item_bytes != sizeof(evr_gpu_tri)) {
        bad = "not a tree of this build of evray";
    } else if (h.num_nodes == 0 ||
               (uint64_t)sb.st_size != sizeof h + (uint64_t)h.num_nodes * node_bytes +
                                           (uint64_t)h.num_items * sizeof(evr_gpu_tri)) {
        bad = "its size does not match its header";
    } else if (!evr_gpu_tree_reserve(c, h.num_nodes, h.num_items)) {
        fclose(f);
        return 0; /* out of memory: the build says so */
    }
    if (!bad) {
        XXH3_state_t *st = XXH3_createState();
        nodes = c->layout == EVR_GPU_LAYOUT_CW8 ? (void *)(c->n8 + c->num_nodes)
                                                : (void *)(c->n4 + c->num_nodes);
        if (fread(nodes, node_bytes, h.num_nodes, f) != h.num_nodes ||
            fread(c->tris + c->num_items, sizeof(evr_gpu_tri), h.num_items, f) != h.num_items) {
            bad = "cut short";
        } else if (!st) {
            bad = "no memory to check it";
        } else {
            XXH3_64bits_reset(st);
            XXH3_64bits_update(st, nodes, node_bytes * h.num_nodes);
            XXH3_64bits_update(st, c->tris + c->num_items, sizeof(evr_gpu_tri) * h.num_items);
            if (XXH3_64bits_digest(st) != h.checksum)
                bad = "its content does not match its checksum";
            else if (!tree_valid(c->layout, nodes, h.num_nodes, h.num_items))
                bad = "an index out of range";
        }
        XXH3_freeState(st);
    }
    fclose(f);
    if (bad) {
        note(cache, "built again, the file was damaged:", path, bad);
        return 0;
    }
    evr_gpu_tree_relocate(c->layout, nodes, h.num_nodes, c->num_nodes, c->num_items);
    c->num_nodes += h.num_nodes;
    c->num_items += h.num_items;
    utimensat(AT_FDCWD, path, NULL, 0); /* recently used: the last to be removed */
    cache->loaded++;
    return 1;
}

/* Removes the least recently used trees until the folder's trees take at most max_bytes. */
static void trim(evr_gpu_bvh_cache *cache)
{
    struct entry {
        struct timespec mtime;
        off_t size;
        char name[64];
    } *e = NULL;
    size_t n = 0, cap = 0;
    uint64_t total = 0;
    DIR *d = opendir(cache->dir);
    struct dirent *de;
    if (!d) return;
    while ((de = readdir(d)) != NULL) {
        struct stat sb;
        const size_t len = strlen(de->d_name);
        if (strncmp(de->d_name, "bvh-", 4) != 0 || len < 8 || len >= sizeof e->name ||
            strcmp(de->d_name + len - 7, ".evrbvh") != 0)
            continue;
        if (fstatat(dirfd(d), de->d_name, &sb, 0) != 0) continue;
        if (n == cap) {
            struct entry *m = realloc(e, (cap = cap ? 2 * cap : 32) * sizeof *e);
            if (!m) break;
            e = m;
        }
        e[n].mtime = sb.st_mtim;
        e[n].size = sb.st_size;
        memcpy(e[n].name, de->d_name, len + 1);
        total += (uint64_t)sb.st_size;
        n++;
    }
    while (total > cache->max_bytes && n > 0) {
        size_t oldest = 0;
        for (size_t i = 1; i < n; i++)
            if (e[i].mtime.tv_sec < e[oldest].mtime.tv_sec ||
                (e[i].mtime.tv_sec == e[oldest].mtime.tv_sec &&
                 e[i].mtime.tv_nsec < e[oldest].mtime.tv_nsec))
                oldest = i;
        unlinkat(dirfd(d), e[oldest].name, 0);
        total -= (uint64_t)e[oldest].size;
        e[oldest] = e[--n];
    }
    closedir(d);
    free(e);
}

void evr_gpu_cache_store(evr_gpu_bvh_cache *cache, const uint8_t key[16], const flat_ctx *c,
                         uint32_t first_node, uint32_t first_item)
{
    char path[4096], tmp[4200];
    const size_t node_bytes = evr_gpu_node_size(c->layout);
    file_header h;
    const uint32_t nn = c->num_nodes - first_node, ni = c->num_items - first_item;
    const evr_gpu_tri *items = c->tris + first_item;
    void *nodes = malloc(node_bytes * nn);
    XXH3_state_t *st = XXH3_createState();
    FILE *f;
    int ok;
    key_path(cache, key, path, sizeof path);
    if (!nodes || !st) {
        note(cache, "cannot write", path, "out of memory");
        free(nodes);
        XXH3_freeState(st);
        return;
    }
    memcpy(nodes,
           c->layout == EVR_GPU_LAYOUT_CW8 ? (const void *)(c->n8 + first_node)
                                           : (const void *)(c->n4 + first_node),
           node_bytes * nn);
    evr_gpu_tree_relocate(c->layout, nodes, nn, -(int64_t)first_node, -(int64_t)first_item);
    memset(&h, 0, sizeof h);
    memcpy(h.magic, MAGIC, 8);
    h.format = FORMAT;
    h.layout = (uint32_t)c->layout;
    memcpy(h.key, key, 16);
    h.num_nodes = nn;
    h.num_items = ni;
    h.node_bytes = (uint32_t)node_bytes;
    h.item_bytes = sizeof(evr_gpu_tri);
    XXH3_64bits_reset(st);
    XXH3_64bits_update(st, nodes, node_bytes * nn);
    XXH3_64bits_update(st, items, sizeof *items * ni);
    h.checksum = XXH3_64bits_digest(st);
    XXH3_freeState(st);
    if (evr_mkdir_p(cache->dir) != 0) {
        note(cache, "cannot make the folder", cache->dir, strerror(errno));
        free(nodes);
        return;
    }
    snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
    errno = 0;
    f = fopen(tmp, "wb");
    if (!f) {
        note(cache, "cannot write", tmp, strerror(errno));
        free(nodes);
        return;
    }
    ok = fwrite(&h, sizeof h, 1, f) == 1 && fwrite(nodes, node_bytes, nn, f) == nn &&
         fwrite(items, sizeof *items, ni, f) == ni;
    ok = (fclose(f) == 0) && ok;
    free(nodes);
    if (!ok || rename(tmp, path) != 0) {
        note(cache, "cannot write", tmp, strerror(errno ? errno : EIO));
        unlink(tmp);
        return;
    }
    cache->stored++;
    if (cache->max_bytes) trim(cache);
}
