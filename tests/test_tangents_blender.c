/* Generated tangents (src/scene/tangents.c) against Blender's MikkTSpace: the sphere of
 * tests/material_assets.py with warped uvs given to Blender (tests/blender_tangents.py:
 * Mesh.calc_tangents) and, as Blender holds it (its vertices, normals, uvs and triangles), to
 * evr_mesh_generate_tangents, once as it is and once with u negated (every triangle mirrored).
 * Every face corner's tangent must agree within 0.1 degree and its bitangent sign exactly. Skips (77) without Blender (Debian 12's blender; scripts/test-blender.sh
 * installs it, EVR_BLENDER names another). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "io/json_read.h"
#include "scene/import_internal.h"

static char dir[] = "/tmp/evray_tan_XXXXXX";

static char *read_text(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    char *b = NULL;
    long len;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    len = ftell(f);
    fseek(f, 0, SEEK_SET);
    if (len > 0 && (b = malloc((size_t)len + 1)) && fread(b, 1, (size_t)len, f) != (size_t)len) {
        free(b);
        b = NULL;
    }
    fclose(f);
    *n = (size_t)len;
    return b;
}

/* n numbers of array value a into x; 0 when it has another length. */
static int numbers(const evr_jdoc *d, int a, double *x, int n)
{
    int e, k = 0;
    if (evr_jdoc_count(d, a) != n) return 0;
    for (e = evr_jdoc_first(d, a); e >= 0; e = evr_jdoc_next(d, e))
        x[k++] = evr_jdoc_number(d, e, NAN);
    return 1;
}

static void compare(const evr_jdoc *d, int root, const char *name)
{
    int verts = evr_jdoc_get(d, root, "vertices"), loops = evr_jdoc_get(d, root, "loops"), e;
    int nv = evr_jdoc_count(d, verts), nl = evr_jdoc_count(d, loops), k, sign_ok = 0;
    evr_mesh m;
    double worst = 1.0, x[9];
    int *lv = malloc((size_t)nl * sizeof *lv + 1);
    float *lt = malloc((size_t)nl * 4 * sizeof *lt + 1);
    memset(&m, 0, sizeof m);
    m.num_vertices = (uint32_t)nv;
    m.num_triangles = (uint32_t)(nl / 3);
    m.positions = malloc((size_t)nv * 3 * sizeof(float) + 1);
    m.normals = malloc((size_t)nv * 3 * sizeof(float) + 1);
    m.uvs = malloc((size_t)nv * 2 * sizeof(float) + 1);
    m.indices = malloc((size_t)nl * sizeof(uint32_t) + 1);
    CHECK(nv > 300 && nl > 1500 && nl % 3 == 0);
    if (!lv || !lt || !m.positions || !m.normals || !m.uvs || !m.indices) goto done;
    for (k = 0, e = evr_jdoc_first(d, verts); e >= 0; e = evr_jdoc_next(d, e), k++) {
        CHECK(numbers(d, e, x, 8));
        for (int c = 0; c < 3; c++) m.positions[3 * k + c] = (float)x[c];
        for (int c = 0; c < 3; c++) m.normals[3 * k + c] = (float)x[3 + c];
        m.uvs[2 * k] = (float)x[6];
        m.uvs[2 * k + 1] = (float)x[7];
    }
    for (k = 0, e = evr_jdoc_first(d, loops); e >= 0; e = evr_jdoc_next(d, e), k++) {
        CHECK(numbers(d, e, x, 5) && x[0] >= 0 && x[0] < nv);
        lv[k] = (int)x[0];
        m.indices[k] = (uint32_t)x[0];
        for (int c = 0; c < 4; c++) lt[4 * k + c] = (float)x[1 + c];
    }
    CHECK(evr_mesh_generate_tangents(&m));
    for (k = 0; k < nl && m.tangents; k++) {
        const float *t = &m.tangents[4 * lv[k]], *b = &lt[4 * k];
        double l = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        double c = (t[0] * b[0] + t[1] * b[1] + t[2] * b[2]) / l;
        if (c < worst) worst = c;
        sign_ok += t[3] == b[3];
    }
    printf("test_tangents_blender: %s: %d face corners, worst angle to Blender's tangent %.4f "
           "deg, %d signs equal (first %+g)\n",
           name, nl, acos(worst < 1 ? worst : 1) * 180 / 3.14159265358979, sign_ok, (double)lt[3]);
    CHECK(worst > cos(0.1 * 3.14159265358979 / 180));
    CHECK(sign_ok == nl);
done:
    free(lv);
    free(lt);
    free(m.positions);
    free(m.normals);
    free(m.uvs);
    free(m.indices);
    free(m.tangents);
}

int main(void)
{
    char cmd[1024], path[256];
    const char *blender = getenv("EVR_BLENDER");
    char *json;
    size_t n = 0;
    if (!blender || !blender[0]) {
        if (system("command -v blender >/dev/null 2>&1") != 0) {
            printf("test_tangents_blender: skipped: no Blender (scripts/test-blender.sh installs "
                   "Debian's, EVR_BLENDER names another)\n");
            return 77;
        }
        blender = "blender";
    }
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(cmd, sizeof cmd,
             "%s -b --factory-startup --python-exit-code 1 -P %s/../blender_tangents.py -- "
             "%s/blender.json >%s/blender.log 2>&1",
             blender, EVR_TEST_DATA, dir, dir);
    CHECK(system(cmd) == 0);
    snprintf(path, sizeof path, "%s/blender.json", dir);
    json = read_text(path, &n);
    CHECK(json != NULL);
    if (json) {
        evr_jdoc d;
        int root = evr_jdoc_parse(&d, json, n);
        CHECK(root >= 0);
        if (root >= 0) {
            compare(&d, evr_jdoc_get(&d, root, "ball"), "ball");
            compare(&d, evr_jdoc_get(&d, root, "ball_mirrored"), "ball_mirrored");
        }
        evr_jdoc_free(&d);
    }
    free(json);
    if (!check_failures) {
        snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
        CHECK(system(cmd) == 0);
    }
    return check_report("test_tangents_blender");
}
