/* Generated tangents (src/scene/tangents.c) are the same bits on any number of threads and
 * whether the vertices are welded by the sort or by the hash: a bumpy grid with uv seams
 * (vertices repeated with other uvs, welded by position, normal and uv), mirrored triangles,
 * triangles without a uv gradient and repeated vertices, more than one chunk of triangles; once
 * with signed zeros (-0 is equal to 0 as a float but not in bits: the sort decides) and once
 * without (the hash may), on 1 to 4 threads, against the sort on one thread. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "scene/import_internal.h"

#define NU 181
#define NV 211

static void make_mesh(evr_mesh *m, int signed_zeros)
{
    const uint32_t nv = 2 * NU * NV, nt = 4 * (NU - 1) * (NV - 1);
    memset(m, 0, sizeof *m);
    m->num_vertices = nv;
    m->num_triangles = nt;
    m->positions = malloc(3 * sizeof(float) * nv);
    m->normals = malloc(3 * sizeof(float) * nv);
    m->uvs = malloc(2 * sizeof(float) * nv);
    m->indices = malloc(3 * sizeof(uint32_t) * nt);
    CHECK(m->positions && m->normals && m->uvs && m->indices);
    if (!m->positions || !m->normals || !m->uvs || !m->indices) return;
    /* two copies of the grid's vertices: the second's uvs mirrored in u past the middle row, the
     * same as the first's elsewhere (welded with it) */
    for (uint32_t copy = 0; copy < 2; copy++)
        for (uint32_t j = 0; j < NV; j++)
            for (uint32_t i = 0; i < NU; i++) {
                const uint32_t v = copy * NU * NV + j * NU + i;
                const float x = (float)i / (NU - 1), y = (float)j / (NV - 1);
                const float h = 0.05f * sinf(17.0f * x) * cosf(13.0f * y);
                float n[3] = {-0.05f * 17.0f * cosf(17.0f * x) * cosf(13.0f * y),
                              0.05f * 13.0f * sinf(17.0f * x) * sinf(13.0f * y), 1.0f};
                const float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                m->positions[3 * v] = x - 0.5f;
                m->positions[3 * v + 1] = y - 0.5f;
                m->positions[3 * v + 2] = signed_zeros && i % 7 == 0 ? -0.0f : h;
                for (int k = 0; k < 3; k++) m->normals[3 * v + k] = n[k] / l;
                m->uvs[2 * v] = copy && j > NV / 2 ? 1.0f - 2.0f * x : 2.0f * x;
                m->uvs[2 * v + 1] = j % 11 == 0 ? 0.0f : 3.0f * y; /* flat rows: no gradient */
                if (!signed_zeros) { /* x + 0 turns -0 (sin(0) times a negative) into +0 */
                    for (int k = 0; k < 3; k++) {
                        m->positions[3 * v + k] += 0.0f;
                        m->normals[3 * v + k] += 0.0f;
                    }
                    m->uvs[2 * v] += 0.0f;
                    m->uvs[2 * v + 1] += 0.0f;
                }
            }
    uint32_t t = 0;
    for (uint32_t copy = 0; copy < 2; copy++)
        for (uint32_t j = 0; j + 1 < NV; j++)
            for (uint32_t i = 0; i + 1 < NU; i++) {
                const uint32_t o = copy * NU * NV, a = o + j * NU + i, b = a + 1, c = a + NU + 1,
                               d = a + NU;
                const uint32_t tri[6] = {a, b, c, a, c, d};
                memcpy(m->indices + 3 * (size_t)t, tri, sizeof tri);
                t += 2;
            }
}

static void same_tangents(int signed_zeros)
{
    evr_mesh m;
    make_mesh(&m, signed_zeros);
    CHECK(m.num_triangles > 65536); /* more than one chunk */
    CHECK(evr_mesh_tangents_threads(&m, 1, 1));
    float *one = m.tangents;
    for (int threads = 1; threads <= 4 && one; threads++)
        for (int by_sort = 0; by_sort < 2; by_sort++) {
            m.tangents = NULL;
            CHECK(evr_mesh_tangents_threads(&m, threads, by_sort));
            CHECK(m.tangents && !memcmp(one, m.tangents, 4 * sizeof(float) * m.num_vertices));
            free(m.tangents);
        }
    /* and what the import calls, however many processors this machine has */
    m.tangents = NULL;
    CHECK(evr_mesh_generate_tangents(&m));
    CHECK(m.tangents && one && !memcmp(one, m.tangents, 4 * sizeof(float) * m.num_vertices));
    /* unit tangents with a sign */
    for (uint32_t v = 0; one && v < m.num_vertices; v += 97) {
        const float *t = one + 4 * v;
        CHECK_NEAR(t[0] * t[0] + t[1] * t[1] + t[2] * t[2], 1.0, 1e-4);
        CHECK(t[3] == 1.0f || t[3] == -1.0f);
    }
    free(one);
    free(m.tangents);
    free(m.positions);
    free(m.normals);
    free(m.uvs);
    free(m.indices);
}

int main(void)
{
    same_tangents(1);
    same_tangents(0);
    return check_report("test_tangents_par");
}
