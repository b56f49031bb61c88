/* The glTF JSON read directly (the .gltf text or the GLB's JSON chunk), for what Assimp 5.2
 * drops or mangles: which channels exist and their interpolation (quirks (d), (e), (f) and STEP
 * in import.c), the nodes' morph weights (quirk (h)) and the lights' radii (a
 * KHR_lights_punctual light's extras "radius", which Assimp does not keep). The materials are
 * read from the JSON in import_gltf_material.c. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/json_read.h"
#include "scene/import_internal.h"

#define NAME_CAP 1024

void evr_gltf_side_free(gltf_side *g)
{
    int i;
    for (i = 0; i < g->num_nodes && g->node_names; i++) free(g->node_names[i]);
    free(g->node_names);
    free(g->ch);
    free(g->light_radius);
    for (i = 0; i < g->num_nodes && g->node_weights; i++) free(g->node_weights[i]);
    free(g->node_weights);
    free(g->node_num_weights);
    memset(g, 0, sizeof *g);
}

static int side_channel_cmp(const void *pa, const void *pb)
{
    const side_channel *a = pa, *b = pb;
    int c = strcmp(a->node, b->node);
    if (c) return c;
    if (a->anim != b->anim) return a->anim < b->anim ? -1 : 1;
    return a->path - b->path;
}

int evr_gltf_index(const evr_jdoc *d, int v)
{
    double x = evr_jdoc_number(d, v, -1);
    return x >= 0 && x < 2147483647.0 && x == (int)x ? (int)x : -1;
}

int evr_gltf_json_span(const unsigned char *data, size_t size, const char **json, size_t *len)
{
    if (size >= 20 && !memcmp(data, "glTF", 4)) {
        uint32_t clen = (uint32_t)data[12] | (uint32_t)data[13] << 8 | (uint32_t)data[14] << 16 |
                        (uint32_t)data[15] << 24;
        if (memcmp(data + 16, "JSON", 4) || (size_t)clen > size - 20) return 0;
        *json = (const char *)data + 20;
        *len = clen;
        return 1;
    }
    *json = (const char *)data;
    *len = size;
    return 1;
}

evr_status evr_gltf_side_parse(const unsigned char *data, size_t size, gltf_side *g, evr_error *err)
{
    evr_jdoc d;
    int root, nodes, anims, lights, i, a, m, cap = 0;
    int *samplers = NULL;
    const char *json;
    size_t jlen;
    evr_status st = EVR_OK;
    memset(g, 0, sizeof *g);
    if (!evr_gltf_json_span(data, size, &json, &jlen))
        return evr_import_fail(err, EVR_ERR_FORMAT, "glTF: the GLB has no JSON chunk");
    root = evr_jdoc_parse(&d, json, jlen);
    if (root < 0 || evr_jdoc_type(&d, root) != EVR_JDOC_OBJECT) {
        st = d.failed ? evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON")
                      : evr_import_fail(err, EVR_ERR_FORMAT,
                                        "glTF: cannot parse the JSON near byte %zu", d.pos);
        evr_jdoc_free(&d);
        return st;
    }

    nodes = evr_jdoc_get(&d, root, "nodes");
    anims = evr_jdoc_get(&d, root, "animations");
    g->num_nodes = evr_jdoc_count(&d, nodes);
    g->num_anims = evr_jdoc_count(&d, anims);
    g->num_materials = evr_jdoc_count(&d, evr_jdoc_get(&d, root, "materials"));
    lights = evr_jdoc_get(
        &d, evr_jdoc_get(&d, evr_jdoc_get(&d, root, "extensions"), "KHR_lights_punctual"),
        "lights");
    g->num_lights = evr_jdoc_count(&d, lights);
    g->light_radius = calloc((size_t)g->num_lights + 1, sizeof *g->light_radius);
    g->node_names = calloc((size_t)g->num_nodes + 1, sizeof *g->node_names);
    g->node_num_weights = calloc((size_t)g->num_nodes + 1, sizeof *g->node_num_weights);
    g->node_weights = calloc((size_t)g->num_nodes + 1, sizeof *g->node_weights);
    if (!g->node_names || !g->node_num_weights || !g->node_weights || !g->light_radius) goto nomem;

    for (i = 0, m = g->num_nodes ? evr_jdoc_first(&d, nodes) : -1; m >= 0;
         m = evr_jdoc_next(&d, m), i++) {
        char buf[NAME_CAP];
        if (!evr_jdoc_string(&d, evr_jdoc_get(&d, m, "name"), buf, sizeof buf) || !buf[0])
            snprintf(buf, sizeof buf, "nodes[%d]", i);
        g->node_names[i] = malloc(strlen(buf) + 1);
        if (!g->node_names[i]) goto nomem;
        strcpy(g->node_names[i], buf);
        {
            int w = evr_jdoc_get(&d, m, "weights"), e, k = 0;
            int nw = evr_jdoc_count(&d, w);
            if (nw > 0) {
                if (!(g->node_weights[i] = malloc((size_t)nw * sizeof(float)))) goto nomem;
                for (e = evr_jdoc_first(&d, w); e >= 0; e = evr_jdoc_next(&d, e))
                    g->node_weights[i][k++] = (float)evr_jdoc_number(&d, e, 0.0);
                g->node_num_weights[i] = nw;
            }
        }
    }
    for (a = 0, i = g->num_anims ? evr_jdoc_first(&d, anims) : -1; i >= 0;
         i = evr_jdoc_next(&d, i), a++) {
        int samps = evr_jdoc_get(&d, i, "samplers"), nsamp = evr_jdoc_count(&d, samps), c, k;
        int chans = evr_jdoc_get(&d, i, "channels");
        free(samplers);
        samplers = malloc(((size_t)nsamp + 1) * sizeof *samplers);
        if (!samplers) goto nomem;
        for (k = 0, c = nsamp ? evr_jdoc_first(&d, samps) : -1; c >= 0; c = evr_jdoc_next(&d, c))
            samplers[k++] = c;
        for (c = evr_jdoc_count(&d, chans) ? evr_jdoc_first(&d, chans) : -1; c >= 0;
             c = evr_jdoc_next(&d, c)) {
            int tgt = evr_jdoc_get(&d, c, "target");
            double si = evr_jdoc_number(&d, evr_jdoc_get(&d, c, "sampler"), -1);
            double ni = evr_jdoc_number(&d, evr_jdoc_get(&d, tgt, "node"), -1);
            char path[32], interp[32];
            side_channel sc;
            evr_jdoc_string(&d, evr_jdoc_get(&d, tgt, "path"), path, sizeof path);
            if (!strcmp(path, "translation")) sc.path = PATH_T;
            else if (!strcmp(path, "rotation")) sc.path = PATH_R;
            else if (!strcmp(path, "scale")) sc.path = PATH_S;
            else if (!strcmp(path, "weights")) sc.path = PATH_W;
            else continue;
            if (!(si >= 0 && si < nsamp) || !(ni >= 0 && ni < g->num_nodes)) continue;
            if (!evr_jdoc_string(&d, evr_jdoc_get(&d, samplers[(int)si], "interpolation"), interp,
                                 sizeof interp))
                strcpy(interp, "LINEAR");
            sc.interp = !strcmp(interp, "STEP")          ? GL_STEP
                        : !strcmp(interp, "CUBICSPLINE") ? GL_CUBIC
                                                         : GL_LINEAR;
            sc.node = g->node_names[(int)ni];
            sc.anim = a;
            if (g->num_ch == cap) {
                int ncap = cap ? cap * 2 : 64;
                side_channel *nc = realloc(g->ch, (size_t)ncap * sizeof *nc);
                if (!nc) goto nomem;
                g->ch = nc;
                cap = ncap;
            }
            g->ch[g->num_ch++] = sc;
        }
    }
    if (g->num_ch) qsort(g->ch, (size_t)g->num_ch, sizeof *g->ch, side_channel_cmp);
    for (i = 0, m = g->num_lights ? evr_jdoc_first(&d, lights) : -1; m >= 0;
         m = evr_jdoc_next(&d, m), i++) {
        double r =
            evr_jdoc_number(&d, evr_jdoc_get(&d, evr_jdoc_get(&d, m, "extras"), "radius"), 0.0);
        g->light_radius[i] = r > 0.0 && r < 1e30 ? (float)r : 0.0f; /* bad values: a point */
    }
    free(samplers);
    evr_jdoc_free(&d);
    return EVR_OK;
nomem:
    free(samplers);
    evr_jdoc_free(&d);
    evr_gltf_side_free(g);
    return evr_import_fail(err, EVR_ERR_NOMEM, "out of memory reading the glTF JSON");
}

int evr_gltf_side_interp(const gltf_side *g, int anim, const char *name, int path)
{
    int lo = 0, hi = g->num_ch, i;
    while (lo < hi) { /* first channel whose node name is >= name */
        int mid = lo + (hi - lo) / 2;
        if (strcmp(g->ch[mid].node, name) < 0) lo = mid + 1;
        else hi = mid;
    }
    for (i = lo; i < g->num_ch && !strcmp(g->ch[i].node, name); i++)
        if ((anim < 0 || g->ch[i].anim == anim) && g->ch[i].path == path) return g->ch[i].interp;
    return -1;
}
