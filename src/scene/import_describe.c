/* evr_scene_describe: what `evray info` prints about an imported scene. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/import_internal.h"

/* A growable text buffer. */
typedef struct {
    char *buf;
    size_t len, cap;
    int failed;
} strbuf;

static void sb_printf(strbuf *b, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (b->failed) return;
    for (;;) {
        size_t room = b->cap - b->len;
        va_start(ap, fmt);
        n = vsnprintf(b->buf ? b->buf + b->len : NULL, b->buf ? room : 0, fmt, ap);
        va_end(ap);
        if (n < 0) {
            b->failed = 1;
            return;
        }
        if (b->buf && (size_t)n < room) {
            b->len += (size_t)n;
            return;
        }
        {
            size_t ncap = b->cap ? b->cap * 2 : 1024;
            char *nb;
            while (ncap < b->len + (size_t)n + 1) ncap *= 2;
            nb = realloc(b->buf, ncap);
            if (!nb) {
                b->failed = 1;
                return;
            }
            b->buf = nb;
            b->cap = ncap;
        }
    }
}

static const char *node_label(const evr_scene *s, int node)
{
    return (node >= 0 && node < s->num_nodes) ? s->nodes[node].name : "(world)";
}

static void describe_curve(strbuf *b, const char *what, const evr_curve *c)
{
    if (c->num_keys <= 0) return;
    sb_printf(b, " %s %d key%s %s", what, c->num_keys, c->num_keys == 1 ? "" : "s",
              c->interp == EVR_INTERP_STEP ? "step" : "linear");
}

/* The shortest %g text that reads back as exactly v: a clip's duration given as printed to
 * `evray render --duration` is the clip's end, not a rounding of it. */
static void exact_number(char *buf, size_t cap, double v)
{
    int digits;
    for (digits = 1; digits < 17; digits++) {
        snprintf(buf, cap, "%.*g", digits, v);
        if (strtod(buf, NULL) == v) return;
    }
    snprintf(buf, cap, "%.17g", v);
}

static void describe_clips(strbuf *b, const evr_scene *s, int max_list)
{
    int a, played = 0;
    for (a = 0; a < s->num_animations; a++) played += s->clips[a].played;
    sb_printf(b, "clips: %d, %d play%s", s->num_animations, played, played == 1 ? "s" : "");
    if (s->clip_choice == EVR_CLIPS_ALL)
        sb_printf(b, " (--animation all: where two animate a property, the first one's keys)");
    else if (s->clip_choice == EVR_CLIPS_ONE) sb_printf(b, " (chosen with --animation)");
    else if (played < s->num_animations)
        sb_printf(b, " (by default a clip plays unless it animates a node that an earlier played "
                     "clip animates; --animation NAME|INDEX|all chooses)");
    sb_printf(b, "\n");
    for (a = 0; a < s->num_animations && a < max_list; a++) {
        const evr_clip *c = &s->clips[a];
        char end[32], start[32];
        exact_number(end, sizeof end, c->end);
        exact_number(start, sizeof start, c->start);
        if (c->name[0]) sb_printf(b, "  [%d] \"%s\": ", a, c->name);
        else sb_printf(b, "  [%d] (unnamed): ", a);
        /* played clips run from time 0: the duration that plays one to its end is its end */
        sb_printf(b, "duration %s s (keys %s s to %s s), %d animated node%s, ", end, start, end,
                  c->num_nodes, c->num_nodes == 1 ? "" : "s");
        if (c->played) sb_printf(b, "plays\n");
        else if (c->conflict >= 0)
            sb_printf(b, "not played: it animates a node that [%d] \"%s\" animates\n", c->conflict,
                      s->clips[c->conflict].name);
        else sb_printf(b, "not played: not chosen\n");
    }
    if (s->num_animations > max_list)
        sb_printf(b, "  ... and %d more\n", s->num_animations - max_list);
}

/* Each skinned mesh: its joints (the first few by node name) and influences per vertex. */
static void describe_skins(strbuf *b, const evr_scene *s, int max_list)
{
    int i, n = 0, listed = 0;
    for (i = 0; i < s->num_meshes; i++) n += s->meshes[i].skin != NULL;
    if (!n) return;
    sb_printf(b, "skins: %d\n", n);
    for (i = 0; i < s->num_meshes && listed < max_list; i++) {
        const evr_skin *sk = s->meshes[i].skin;
        int j;
        if (!sk) continue;
        listed++;
        sb_printf(b, "  [%d] \"%s\": %d joint%s (", i, s->meshes[i].name, sk->num_joints,
                  sk->num_joints == 1 ? "" : "s");
        for (j = 0; j < sk->num_joints && j < 8; j++)
            sb_printf(b, "%s\"%s\"", j ? ", " : "", node_label(s, sk->joint_nodes[j]));
        sb_printf(b, "%s), %d influence%s per vertex\n", sk->num_joints > 8 ? ", ..." : "",
                  sk->influences, sk->influences == 1 ? "" : "s");
    }
    if (n > listed) sb_printf(b, "  ... and %d more\n", n - listed);
}

/* Each mesh with morph targets: how many, whether normals move with them, and for each node
 * placing it, its weights at rest and their channel. */
static void describe_morphs(strbuf *b, const evr_scene *s, int max_list)
{
    int i, k, n = 0, listed = 0;
    for (i = 0; i < s->num_meshes; i++) n += s->meshes[i].morph != NULL;
    if (!n) return;
    sb_printf(b, "morph targets: %d mesh%s\n", n, n == 1 ? "" : "es");
    for (i = 0; i < s->num_meshes && listed < max_list; i++) {
        const evr_morph *mo = s->meshes[i].morph;
        if (!mo) continue;
        listed++;
        sb_printf(b, "  [%d] \"%s\": %d target%s, %s\n", i, s->meshes[i].name, mo->num_targets,
                  mo->num_targets == 1 ? "" : "s",
                  mo->d_normals ? "normal deltas" : "no normal deltas (normals follow positions)");
        for (k = 0; k < s->num_instances; k++) {
            const evr_node *nd;
            const evr_curve *c;
            int j;
            if (s->instances[k].mesh != i) continue;
            nd = &s->nodes[s->instances[k].node];
            c = &nd->w_curve;
            sb_printf(b, "    node \"%s\": weights (", nd->name);
            for (j = 0; j < nd->num_weights && j < 8; j++)
                sb_printf(b, "%s%.4g", j ? " " : "", nd->weights[j]);
            sb_printf(b, "%s)", nd->num_weights > 8 ? " ..." : "");
            if (c->num_keys > 0)
                sb_printf(b, ", channel %d key%s %s, %.4g s to %.4g s\n", c->num_keys,
                          c->num_keys == 1 ? "" : "s",
                          c->interp == EVR_INTERP_STEP ? "step" : "linear", c->times[0],
                          c->times[c->num_keys - 1]);
            else sb_printf(b, ", no channel\n");
        }
    }
    if (n > listed) sb_printf(b, "  ... and %d more\n", n - listed);
}

/* Each material's model in one line: factors, textures, alpha, transmission and the rest that
 * differs from the defaults. */
static void describe_materials(strbuf *b, const evr_scene *s, int max_list)
{
    static const char *slot_names[EVR_TEX_COUNT] = {
        "base", "metallic-roughness", "normal", "occlusion", "emissive", "transmission"};
    int i, k, listed = 0;
    for (i = 0; i < s->num_materials && listed < max_list; i++, listed++) {
        const evr_material_params *p = &s->materials[i].p;
        const char *sep = ", textures: ";
        sb_printf(b, "  [%d] \"%s\": base (%.3g %.3g %.3g", i, s->materials[i].name,
                  p->base_color[0], p->base_color[1], p->base_color[2]);
        if (p->base_color[3] != 1.0f) sb_printf(b, " alpha %.3g", p->base_color[3]);
        sb_printf(b, "), metal %.3g rough %.3g", p->metallic, p->roughness);
        for (k = 0; k < EVR_TEX_COUNT; k++) {
            const evr_texture_ref *t = &p->tex[k];
            int moved = t->xf[0] != 1.0f || t->xf[1] != 0.0f || t->xf[2] != 0.0f ||
                        t->xf[3] != 0.0f || t->xf[4] != 1.0f || t->xf[5] != 0.0f;
            if (t->index < 0) continue;
            sb_printf(b, "%s%s", sep, slot_names[k]);
            if ((k == EVR_TEX_NORMAL || k == EVR_TEX_OCCLUSION) && t->scale != 1.0f)
                sb_printf(b, " %.3g", t->scale);
            if (moved) sb_printf(b, " (transformed)");
            sep = ", ";
        }
        if (p->emissive[0] != 0.0f || p->emissive[1] != 0.0f || p->emissive[2] != 0.0f)
            sb_printf(b, "; emissive (%.3g %.3g %.3g)", p->emissive[0], p->emissive[1],
                      p->emissive[2]);
        if (p->alpha_mode == EVR_ALPHA_MASK) sb_printf(b, "; alpha mask %.3g", p->alpha_cutoff);
        else if (p->alpha_mode == EVR_ALPHA_BLEND) sb_printf(b, "; alpha blend");
        if (p->transmission > 0.0f || p->tex[EVR_TEX_TRANSMISSION].index >= 0)
            sb_printf(b, "; transmission %.3g", p->transmission);
        if (p->ior != 1.5f || p->transmission > 0.0f) sb_printf(b, "; ior %.4g", p->ior);
        if (p->thickness > 0.0f || isfinite(p->attenuation_distance))
            sb_printf(b, "; volume thickness %.3g attenuation %.3g (%.3g %.3g %.3g)", p->thickness,
                      p->attenuation_distance, p->attenuation_color[0], p->attenuation_color[1],
                      p->attenuation_color[2]);
        if (p->specular != 1.0f || p->specular_color[0] != 1.0f || p->specular_color[1] != 1.0f ||
            p->specular_color[2] != 1.0f)
            sb_printf(b, "; specular %.3g (%.3g %.3g %.3g)", p->specular, p->specular_color[0],
                      p->specular_color[1], p->specular_color[2]);
        if (p->unlit) sb_printf(b, "; unlit");
        if (p->double_sided) sb_printf(b, "; double-sided");
        sb_printf(b, "\n");
    }
    if (s->num_materials > listed) sb_printf(b, "  ... and %d more\n", s->num_materials - listed);
}

char *evr_scene_describe(const evr_scene *s)
{
    strbuf b;
    int i, animated = 0;
    uint64_t tris = 0, verts = 0, inst_tris = 0;
    static const char *light_types[3] = {"point", "spot", "directional"};
    const int max_list = 50;
    char a_start[32], a_end[32];

    memset(&b, 0, sizeof b);
    if (!s) return NULL;
    sb_printf(&b, "scene: %s\n", s->source);
    if (s->format[0]) sb_printf(&b, "format: %s\n", s->format);

    sb_printf(&b, "cameras: %d\n", s->num_cameras);
    for (i = 0; i < s->num_cameras; i++) {
        const evr_camera_desc *c = &s->cameras[i];
        sb_printf(&b, "  [%d] \"%s\" node \"%s\", ", i, c->name, node_label(s, c->node));
        if (c->ortho) sb_printf(&b, "orthographic, %.4g high", 2.0 * c->ymag);
        else if (c->xfov > 0.0f)
            sb_printf(&b, "xfov %.2f deg (yfov from the image's aspect)",
                      c->xfov * 180.0 / EVR_PI_D);
        else sb_printf(&b, "yfov %.2f deg", c->yfov * 180.0 / EVR_PI_D);
        if (c->aspect > 0.0f) sb_printf(&b, ", aspect %.4g", c->aspect);
        sb_printf(&b, ", znear %.4g%s\n", c->znear,
                  c->automatic ? ", automatic (the file has no camera)" : "");
    }

    sb_printf(&b, "lights: %d%s\n", s->num_lights,
              s->default_light ? " (the file has none: default headlight added)" : "");
    for (i = 0; i < s->num_lights; i++) {
        const evr_light *l = &s->lights[i];
        float k = fmaxf(l->color[0], fmaxf(l->color[1], l->color[2]));
        sb_printf(&b, "  [%d] \"%s\" %s, node \"%s\", colour (%.3g %.3g %.3g), intensity %.4g %s",
                  i, l->name, light_types[l->type <= 2 ? l->type : 0], node_label(s, l->node),
                  k > 0 ? l->color[0] / k : 0.0, k > 0 ? l->color[1] / k : 0.0,
                  k > 0 ? l->color[2] / k : 0.0, k, l->type == EVR_LIGHT_DIRECTIONAL ? "lx" : "cd");
        if (l->type == EVR_LIGHT_SPOT)
            sb_printf(&b, ", cone %.1f-%.1f deg (half angles)", l->inner_cone * 180.0 / EVR_PI_D,
                      l->outer_cone * 180.0 / EVR_PI_D);
        if (l->radius > 0.0f) sb_printf(&b, ", radius %.4g m", l->radius);
        sb_printf(&b, "\n");
    }

    if (s->num_animations) describe_clips(&b, s, max_list);
    for (i = 0; i < s->num_nodes; i++)
        animated += s->nodes[i].animated || s->nodes[i].w_curve.num_keys > 0;
    /* exact, like the clips' durations: the end is what --duration takes to play it all */
    exact_number(a_start, sizeof a_start, s->anim_start);
    exact_number(a_end, sizeof a_end, s->anim_end);
    if (animated) {
        int listed = 0;
        sb_printf(&b, "animation: %s s to %s s, %d animated node%s", a_start, a_end, animated,
                  animated == 1 ? "" : "s");
        if (s->frame_rate > 0) sb_printf(&b, ", %.4g frames/s", s->frame_rate);
        sb_printf(&b, "\n");
        for (i = 0; i < s->num_nodes && listed < max_list; i++) {
            const evr_node *n = &s->nodes[i];
            if (!n->animated && n->w_curve.num_keys <= 0) continue;
            listed++;
            sb_printf(&b, "  \"%s\":", n->name);
            describe_curve(&b, "translation", &n->t_curve);
            describe_curve(&b, "rotation", &n->r_curve);
            describe_curve(&b, "scale", &n->s_curve);
            describe_curve(&b, "morph weights", &n->w_curve);
            sb_printf(&b, "\n");
        }
        if (animated > listed) sb_printf(&b, "  ... and %d more\n", animated - listed);
    } else if (s->anim_end > s->anim_start) { /* played clips whose curves hold the rest pose */
        sb_printf(&b, "animation: %s s to %s s, no node moves\n", a_start, a_end);
    } else {
        sb_printf(&b, "animation: none (static scene)\n");
    }

    for (i = 0; i < s->num_meshes; i++) {
        tris += s->meshes[i].num_triangles;
        verts += s->meshes[i].num_vertices;
    }
    for (i = 0; i < s->num_instances; i++)
        inst_tris += s->meshes[s->instances[i].mesh].num_triangles;
    sb_printf(&b, "meshes: %d, %llu vertices, %llu triangles\n", s->num_meshes,
              (unsigned long long)verts, (unsigned long long)tris);
    for (i = 0; i < s->num_meshes && i < max_list; i++) {
        const evr_mesh *m = &s->meshes[i];
        sb_printf(&b, "  [%d] \"%s\": %u vertices, %u triangles, material \"%s\"\n", i, m->name,
                  m->num_vertices, m->num_triangles,
                  (m->material >= 0 && m->material < s->num_materials)
                      ? s->materials[m->material].name
                      : "?");
    }
    if (s->num_meshes > max_list) sb_printf(&b, "  ... and %d more\n", s->num_meshes - max_list);
    describe_skins(&b, s, max_list);
    describe_morphs(&b, s, max_list);
    sb_printf(&b, "instances: %d (%llu triangles in the scene), nodes: %d\n", s->num_instances,
              (unsigned long long)inst_tris, s->num_nodes);
    sb_printf(&b, "materials: %d, textures: %d\n", s->num_materials, s->num_textures);
    describe_materials(&b, s, max_list);
    sb_printf(&b, "bounds (rest pose): (%.4g %.4g %.4g) to (%.4g %.4g %.4g), size %.4g\n",
              s->bounds_min.x, s->bounds_min.y, s->bounds_min.z, s->bounds_max.x, s->bounds_max.y,
              s->bounds_max.z, evr_v3_len(evr_v3_sub(s->bounds_max, s->bounds_min)));
    if (s->num_warnings) {
        const char *w = evr_scene_warnings(s), *nl;
        sb_printf(&b, "warnings: %d\n", s->num_warnings);
        for (; (nl = strchr(w, '\n')) != NULL; w = nl + 1)
            sb_printf(&b, "  %.*s\n", (int)(nl - w), w);
        if (s->num_warnings > EVR_MAX_WARNINGS)
            sb_printf(&b, "  ... and %d more\n", s->num_warnings - EVR_MAX_WARNINGS);
    }
    if (b.failed) {
        free(b.buf);
        return NULL;
    }
    return b.buf;
}
