/* Whether Assimp's JoinIdenticalVertices would leave a mesh as it is, found in O(n log n) without
 * it: on a 1 M-triangle glTF the step took 0.75 s of a 0.9 s load, to change nothing (an
 * exporter's vertices are already joined). When this says "no change" the step is skipped; in
 * every other case Assimp joins as before, so the scene is the same either way.
 *
 * What Assimp 5.2's step does per mesh: it drops vertices no face uses, and merges a vertex into
 * an earlier one found near its position (SpatialSort) when position, normal, first uv
 * channel, tangent and bitangent (and, with colours or several uv channels, those too) each
 * differ by at most 1e-5 (the length of the difference; Assimp 5.2.4 joins positions 1e-6
 * apart, not 1e-5: tests/test_join.py). Every one of those conditions must hold to merge, so
 * looking at position, normal and uv 0 alone, with wider bounds, finds every pair Assimp could
 * merge and more:
 *   - a pair is near when every coordinate differs by at most POS_TOL (absolute) plus
 *     POS_REL times the mesh's largest coordinate, far wider than a few ULPs and than 1e-5;
 *   - a near pair could merge when every component of its normals and uvs differs by at most
 *     ATTR_TOL (twice 1e-5); absent normals or uvs are equal (Assimp compares zeros).
 * Near pairs are found by sorting the vertices along one direction (a pair within d per
 * coordinate lies within d times the direction's 1-norm along it) and comparing each with the
 * next ones inside that window. A vertex with more than MAX_SCAN neighbours in its window (many
 * vertices at one place), a value that is not finite (Assimp's comparisons treat NaN as equal)
 * or a vertex that no face uses also answers "Assimp must join". */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/scene.h>

#include "scene/import_internal.h"

#define POS_TOL 1e-5f
#define POS_REL 1e-6f
#define ATTR_TOL 2e-5f
#define MAX_SCAN 64

/* the sort direction: no axis or diagonal, so that flat and axis-aligned meshes spread out */
static const float DIR[3] = {0.8523f, 0.0112f, 0.5213f};

typedef struct {
    uint32_t key; /* the projection's bits, ordered as the floats are */
    uint32_t v;
} proj_rec;

static uint32_t float_order(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : u | 0x80000000u;
}

/* LSD radix sort by key, 8 bits a pass; a and tmp hold n records; the result is in a. */
static void radix_sort(proj_rec *a, proj_rec *tmp, size_t n)
{
    for (int shift = 0; shift < 32; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; i++) count[((a[i].key >> shift) & 255u) + 1]++;
        for (int b = 0; b < 256; b++) count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++) tmp[count[(a[i].key >> shift) & 255u]++] = a[i];
        memcpy(a, tmp, n * sizeof *a);
    }
}

static int all_finite(const struct aiVector3D *p, size_t n)
{
    for (size_t i = 0; p && i < n; i++)
        if (!isfinite(p[i].x) || !isfinite(p[i].y) || !isfinite(p[i].z)) return 0;
    return 1;
}

static int close3(const struct aiVector3D *p, uint32_t a, uint32_t b, float tol)
{
    return !p || (fabsf(p[a].x - p[b].x) <= tol && fabsf(p[a].y - p[b].y) <= tol &&
                  fabsf(p[a].z - p[b].z) <= tol);
}

/* 1 when every vertex is used and no two could merge; 0 otherwise or when memory ran out. */
static int mesh_join_is_noop(const struct aiMesh *m)
{
    const size_t n = m->mNumVertices;
    const struct aiVector3D *p = m->mVertices, *nr = m->mNormals, *uv = m->mTextureCoords[0];
    if (!p || !n) return 0;
    if (!all_finite(p, n) || !all_finite(nr, n) || !all_finite(uv, n)) return 0;
    uint8_t *used = calloc(n, 1);
    proj_rec *rec = malloc(n * sizeof *rec), *tmp = malloc(n * sizeof *tmp);
    float *proj = malloc(n * sizeof *proj), *sorted = (float *)tmp;
    int ok = used && rec && tmp && proj;
    float maxabs = 0.0f;
    for (unsigned f = 0; ok && f < m->mNumFaces; f++)
        for (unsigned k = 0; k < m->mFaces[f].mNumIndices; k++) {
            const unsigned v = m->mFaces[f].mIndices[k];
            if (v < n) used[v] = 1;
        }
    for (size_t v = 0; ok && v < n; v++) {
        if (!used[v]) ok = 0;
        maxabs = fmaxf(maxabs, fmaxf(fabsf(p[v].x), fmaxf(fabsf(p[v].y), fabsf(p[v].z))));
    }
    const float tol = POS_TOL + POS_REL * maxabs;
    /* the projections' rounding is below 1e-6 of the largest coordinate: the window allows it */
    const float window = tol * (DIR[0] + DIR[1] + DIR[2]) * 1.01f + 2e-6f * maxabs;
    for (size_t v = 0; ok && v < n; v++) {
        proj[v] = DIR[0] * p[v].x + DIR[1] * p[v].y + DIR[2] * p[v].z;
        rec[v].key = float_order(proj[v]);
        rec[v].v = (uint32_t)v;
    }
    if (ok) radix_sort(rec, tmp, n);
    for (size_t i = 0; ok && i < n; i++) sorted[i] = proj[rec[i].v]; /* tmp is free again */
    for (size_t i = 0; ok && i < n; i++) {
        const float end = sorted[i] + window;
        for (size_t j = i + 1; ok && j < n && sorted[j] <= end; j++) {
            const uint32_t a = rec[i].v, b = rec[j].v;
            if (j - i > MAX_SCAN) ok = 0;
            else if (close3(p, a, b, tol) && close3(nr, a, b, ATTR_TOL) &&
                     close3(uv, a, b, ATTR_TOL))
                ok = 0;
        }
    }
    free(used);
    free(rec);
    free(tmp);
    free(proj);
    return ok;
}

int evr_import_join_is_noop(const struct aiScene *ai)
{
    for (unsigned i = 0; i < ai->mNumMeshes; i++)
        if (!mesh_join_is_noop(ai->mMeshes[i])) return 0;
    return 1;
}
