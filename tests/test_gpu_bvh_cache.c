/* The GPU BVH cache (src/cuda/gpu_bvh_cache.h), on the host: a tree loaded from the folder is the
 * built tree bit for bit (nodes, triangles, roots, stacks, bounds) for both node layouts; a
 * changed mesh misses and is built; a damaged file (a flipped byte, cut short, an index out of
 * range under a valid checksum) is built again and replaced, with a note, and a FIFO in a tree's
 * place is not read (it would block the build) and is replaced; a folder that cannot
 * be made leaves a note and the build goes on; the folder is held to its bound. Every tree of
 * the demo scenes is kept here (min_tris 0); the CUDA backend keeps only big ones. */
#include "check.h"
#include "cuda/gpu_bvh.h"
#include "cuda/gpu_bvh_cache.h"
#include "scene/scene.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

/* the file's header as gpu_bvh_cache.c writes it (format 1) */
#define HDR_NUM_NODES 32
#define HDR_CHECKSUM 48
#define HDR_BYTES 56

static void clear_dir(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *de;
    char p[4096];
    if (!d) return;
    while ((de = readdir(d)) != NULL) {
        if (de->d_name[0] == '.' && (!de->d_name[1] || de->d_name[1] == '.')) continue;
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        unlink(p);
    }
    closedir(d);
}

/* The folder's trees: their count, their bytes in all, and the largest's path. */
static int list_trees(const char *dir, long long *bytes, char *largest, size_t n)
{
    DIR *d = opendir(dir);
    struct dirent *de;
    int count = 0;
    long long best = -1;
    *bytes = 0;
    if (!d) return 0;
    while ((de = readdir(d)) != NULL) {
        struct stat sb;
        char p[4096];
        if (strncmp(de->d_name, "bvh-", 4) != 0) continue;
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        if (stat(p, &sb) != 0) continue;
        count++;
        *bytes += sb.st_size;
        if (sb.st_size > best) {
            best = sb.st_size;
            snprintf(largest, n, "%s", p);
        }
    }
    closedir(d);
    return count;
}

static int same_bytes(const void *a, const void *b, size_t n)
{
    return n == 0 || (a && b && memcmp(a, b, n) == 0);
}

/* b is a's tree bit for bit. */
static int same_tree(const evr_gpu_bvh *a, const evr_gpu_bvh *b)
{
    const size_t g = (size_t)a->num_groups, node = a->layout == EVR_GPU_LAYOUT_CW8
                                                       ? sizeof(evr_gpu_node8)
                                                       : sizeof(evr_gpu_node4);
    return a->layout == b->layout && a->num_groups == b->num_groups &&
           a->num_nodes == b->num_nodes && a->num_tris == b->num_tris &&
           a->num_trees == b->num_trees && a->max_stack == b->max_stack &&
           same_bytes(
               a->layout == EVR_GPU_LAYOUT_CW8 ? (const void *)a->nodes8 : (const void *)a->nodes4,
               b->layout == EVR_GPU_LAYOUT_CW8 ? (const void *)b->nodes8 : (const void *)b->nodes4,
               node * a->num_nodes) &&
           same_bytes(a->tris, b->tris, sizeof *a->tris * a->num_tris) &&
           same_bytes(a->group_root, b->group_root, sizeof(int32_t) * g) &&
           same_bytes(a->group_stack, b->group_stack, sizeof(int) * (size_t)a->num_groups) &&
           same_bytes(a->group_bounds, b->group_bounds, sizeof(float) * 6 * (size_t)a->num_groups);
}

/* Builds s through the cache in dir (min_tris 0, bound max_bytes); checks that the tree is
 * ref's and returns the cache's account. */
static evr_gpu_bvh_cache build(const evr_scene *s, int layout, const char *dir, uint64_t max_bytes,
                               const evr_gpu_bvh *ref)
{
    evr_gpu_bvh b;
    evr_gpu_bvh_cache c;
    evr_gpu_bvh_cache_init(&c, dir);
    c.min_tris = 0;
    c.max_bytes = max_bytes;
    CHECK_OK(evr_gpu_bvh_build(s, layout, &c, &b, &e_));
    if (ref) CHECK(same_tree(ref, &b));
    evr_gpu_bvh_free(&b);
    return c;
}

/* Rewrites the file at path after f changed its bytes, its checksum made to match again when
 * rehash is set. */
static void damage(const char *path, void (*f)(unsigned char *buf, long *n), int rehash)
{
    FILE *fp = fopen(path, "rb");
    unsigned char *buf;
    long n;
    CHECK(fp != NULL);
    if (!fp) return;
    fseek(fp, 0, SEEK_END);
    n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    buf = malloc((size_t)n);
    CHECK(buf && fread(buf, 1, (size_t)n, fp) == (size_t)n);
    fclose(fp);
    f(buf, &n);
    if (rehash) {
        uint64_t h = XXH3_64bits(buf + HDR_BYTES, (size_t)n - HDR_BYTES);
        memcpy(buf + HDR_CHECKSUM, &h, 8);
    }
    fp = fopen(path, "wb");
    CHECK(fp && fwrite(buf, 1, (size_t)n, fp) == (size_t)n);
    if (fp) fclose(fp);
    free(buf);
}
static void flip_byte(unsigned char *buf, long *n) { buf[*n / 2] ^= 0x40; }
static void cut_short(unsigned char *buf, long *n)
{
    (void)buf;
    *n -= 48;
}
/* the root's children placed past the last node (CW8 child_base at byte 16 of a node) */
static void bad_child(unsigned char *buf, long *n)
{
    uint32_t nn, cb;
    (void)n;
    memcpy(&nn, buf + HDR_NUM_NODES, 4);
    cb = nn;
    memcpy(buf + HDR_BYTES + 16, &cb, 4);
}

static void test_scene(const char *name, const char *dir)
{
    evr_scene *s = NULL;
    evr_error err;
    const int layouts[2] = {EVR_GPU_LAYOUT_CW8, EVR_GPU_LAYOUT_BVH4};
    CHECK_OK(evr_demo_load(name, &s, &err));
    if (!s) return;
    for (int li = 0; li < 2; li++) {
        evr_gpu_bvh ref;
        evr_gpu_bvh_cache c;
        char largest[4096] = "", what[128];
        long long bytes = 0, all = 0;
        int files;
        clear_dir(dir);
        CHECK_OK(evr_gpu_bvh_build(s, layouts[li], NULL, &ref, &e_));
        /* the first run writes every tree (a tree of the same triangles as one before it is
         * read back), the second reads them all */
        c = build(s, layouts[li], dir, 0, &ref);
        CHECK(c.loaded + c.stored == ref.num_trees && c.stored > 0 && !c.note[0]);
        files = list_trees(dir, &all, largest, sizeof largest);
        CHECK(files == c.stored);
        c = build(s, layouts[li], dir, 0, &ref);
        CHECK(c.loaded == ref.num_trees && c.stored == 0 && !c.note[0]);
        printf("%s, %s: %d trees, %d files, %lld bytes\n", name,
               layouts[li] == EVR_GPU_LAYOUT_CW8 ? "cw8" : "bvh4", ref.num_trees, files, all);
        /* damaged files: built again (the same tree), replaced, and said */
        void (*harm[3])(unsigned char *, long *) = {flip_byte, cut_short, bad_child};
        const char *said[3] = {"checksum", "size", "out of range"};
        for (int k = 0; k < 3; k++) {
            if (k == 2 && layouts[li] != EVR_GPU_LAYOUT_CW8) continue;
            damage(largest, harm[k], k == 2);
            c = build(s, layouts[li], dir, 0, &ref);
            snprintf(what, sizeof what, "%s", said[k]);
            CHECK(strstr(c.note, what) != NULL && strstr(c.note, "damaged") != NULL);
            if (!strstr(c.note, what)) fprintf(stderr, "note: %s\n", c.note);
            CHECK(c.stored == 1 && c.loaded == ref.num_trees - 1);
            c = build(s, layouts[li], dir, 0, &ref);
            CHECK(c.loaded == ref.num_trees && !c.note[0]);
        }
        /* a bound on the folder: the least recently used go first as trees are written */
        clear_dir(dir);
        c = build(s, layouts[li], dir, (uint64_t)(all / 2), &ref);
        files = list_trees(dir, &bytes, largest, sizeof largest);
        CHECK(bytes <= all / 2 && !c.note[0]);
        evr_gpu_bvh_free(&ref);
    }
    /* a changed mesh: its tree misses and is built; the others still hit */
    {
        evr_gpu_bvh ref;
        evr_gpu_bvh_cache c;
        int m = 0;
        clear_dir(dir);
        c = build(s, 0, dir, 0, NULL);
        for (int i = 1; i < s->num_meshes; i++)
            if (s->meshes[i].num_triangles > s->meshes[m].num_triangles) m = i;
        s->meshes[m].positions[0] += 1e-3f;
        CHECK_OK(evr_gpu_bvh_build(s, 0, NULL, &ref, &e_));
        c = build(s, 0, dir, 0, &ref);
        CHECK(c.stored >= 1 && c.loaded + c.stored == ref.num_trees && c.loaded >= 1);
        evr_gpu_bvh_free(&ref);
    }
    evr_scene_release(s);
}

int main(void)
{
    char dir[] = "/tmp/evray-bvh-cache-XXXXXX", sub[4200], file[4200];
    FILE *f;
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_scene("eye", dir);
    test_scene("city", dir);
    /* a folder that cannot be made (under a file): a note, the build goes on and is the same */
    {
        evr_scene *s = NULL;
        evr_error err;
        evr_gpu_bvh ref;
        evr_gpu_bvh_cache c;
        clear_dir(dir);
        snprintf(file, sizeof file, "%s/a-file", dir);
        snprintf(sub, sizeof sub, "%s/a-file/bvh", dir);
        f = fopen(file, "w");
        CHECK(f != NULL);
        if (f) fclose(f);
        CHECK_OK(evr_demo_load("square", &s, &err));
        if (s) {
            CHECK_OK(evr_gpu_bvh_build(s, 0, NULL, &ref, &e_));
            c = build(s, 0, sub, 0, &ref);
            CHECK(c.stored == 0 && c.loaded == 0 && strstr(c.note, "cannot make the folder"));
            printf("note: %s\n", c.note);
            /* a FIFO in a tree's place is not read (it would block), and is replaced */
            {
                char largest[4096] = "";
                long long bytes;
                clear_dir(dir);
                build(s, 0, dir, 0, &ref);
                CHECK(list_trees(dir, &bytes, largest, sizeof largest) >= 1);
                CHECK(unlink(largest) == 0 && mkfifo(largest, 0600) == 0);
                c = build(s, 0, dir, 0, &ref);
                CHECK(strstr(c.note, "cannot read") && strstr(c.note, "FIFO"));
                CHECK(c.stored == 1 && c.loaded == ref.num_trees - 1);
                c = build(s, 0, dir, 0, &ref);
                CHECK(c.loaded == ref.num_trees && !c.note[0]);
                printf("note: %s\n", c.note[0] ? c.note : "(none on the next run)");
            }
            evr_gpu_bvh_free(&ref);
            evr_scene_release(s);
        }
    }
    clear_dir(dir);
    rmdir(dir);
    return check_report("test_gpu_bvh_cache");
}
