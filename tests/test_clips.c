/* Which animation clips play (scene/import_clips.c) and the load options that choose them
 * (evr_scene_load_with, evr_scene_load_memory_with, evr_load_options' size). Scene file:
 * tests/data/import/clips.gltf (made by make_data.py there): nodes a, b, c; clips
 *   0 walk  a translation +X (2 at 1 s)         2 wave  b rotation, keys to 1.3 s
 *   1 run   a translation +Y (3 at 0.5 s), scale  3 blink a's morph weight (0.8 s)
 *   4 (unnamed) c translation, keys 0.25 s to 0.75 s. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "scene/scene.h"

#define CLIPS EVR_TEST_DATA "/import/clips.gltf"

static int node_index(const evr_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->num_nodes; i++)
        if (!strcmp(s->nodes[i].name, name)) return i;
    return -1;
}

/* The last translation key of node `name` (x or y: component 0 or 1), NAN without a curve. */
static double last_translation(const evr_scene *s, const char *name, int comp)
{
    int n = node_index(s, name);
    const evr_curve *c;
    if (n < 0) return NAN;
    c = &s->nodes[n].t_curve;
    return c->num_keys > 0 ? c->values[(size_t)(c->num_keys - 1) * 3 + (size_t)comp] : NAN;
}

static evr_scene *load(const char *animation, evr_error *err)
{
    evr_load_options o;
    evr_scene *s = NULL;
    evr_load_options_defaults(&o);
    o.animation = animation;
    if (evr_scene_load_with(CLIPS, &o, &s, err) != EVR_OK) {
        fprintf(stderr, "clips.gltf with '%s': %s\n", animation ? animation : "(default)",
                err->msg);
        return NULL;
    }
    return s;
}

static void check_played(const evr_scene *s, const char *want)
{
    int a;
    CHECK(s->num_animations == (int)strlen(want));
    for (a = 0; a < s->num_animations && want[a]; a++) {
        CHECK(s->clips[a].played == (want[a] == '1'));
        if (s->clips[a].played != (want[a] == '1')) fprintf(stderr, "  clip %d\n", a);
    }
}

/* The default rule: walk, wave and the unnamed clip play; run and blink share node a with
 * walk (blink through its morph-weight channel) and are named in the notice. */
static void test_default(void)
{
    evr_error err;
    evr_scene *s = load(NULL, &err);
    const char *notice;
    char *text;
    int a;
    CHECK(s != NULL);
    if (!s) return;
    check_played(s, "10101");
    CHECK(s->clip_choice == EVR_CLIPS_DEFAULT);
    CHECK(s->clips[1].conflict == 0 && s->clips[3].conflict == 0);
    CHECK(s->clips[0].conflict == -1 && s->clips[2].conflict == -1);
    for (a = 0; a < s->num_animations; a++) CHECK(s->clips[a].num_nodes == 1);
    CHECK(!strcmp(s->clips[0].name, "walk") && s->clips[4].name[0] == 0);
    CHECK_NEAR(s->clips[0].end, 1.0, 1e-9);
    CHECK_NEAR(s->clips[2].end, 1.3, 1e-6);
    /* Assimp adds rotation and scale keys at 0 s to c's clip: not the clip's keys */
    CHECK_NEAR(s->clips[4].start, 0.25, 1e-6);
    CHECK_NEAR(s->clips[4].end, 0.75, 1e-6);
    CHECK(s->anim_end == s->clips[2].end);              /* exactly: the longest played clip */
    CHECK_NEAR(last_translation(s, "a", 0), 2.0, 1e-6); /* walk's */
    CHECK(s->nodes[node_index(s, "a")].s_curve.num_keys == 0);
    notice = evr_scene_notice(s);
    CHECK(notice != NULL);
    if (notice) {
        CHECK(strstr(notice, "'run', 'blink'") != NULL);
        CHECK(strstr(notice, "'walk' animates") != NULL);
        CHECK(strstr(notice, "--animation") != NULL);
        CHECK(strchr(notice, '\n') == NULL);
    }
    text = evr_scene_describe(s);
    CHECK(text != NULL);
    if (text) {
        CHECK(strstr(text, "clips: 5, 3 play") != NULL);
        CHECK(strstr(text, "[1] \"run\": duration 0.5 s (keys 0 s to 0.5 s), 1 animated node, "
                           "not played: it animates a node that [0] \"walk\" animates") != NULL);
        CHECK(strstr(text, "[4] (unnamed): duration 0.75 s (keys 0.25 s to 0.75 s)") != NULL);
        free(text);
    }
    evr_scene_release(s);
}

/* One clip by name or index: it alone, no notice, the animation as long as it. */
static void test_one(const char *choice)
{
    evr_error err;
    evr_scene *s = load(choice, &err);
    CHECK(s != NULL);
    if (!s) return;
    check_played(s, "01000");
    CHECK(s->clip_choice == EVR_CLIPS_ONE);
    CHECK(evr_scene_notice(s) == NULL);
    CHECK_NEAR(last_translation(s, "a", 1), 3.0, 1e-6); /* run's +Y */
    CHECK(s->nodes[node_index(s, "a")].s_curve.num_keys == 2);
    CHECK(!s->nodes[node_index(s, "b")].animated && !s->nodes[node_index(s, "c")].animated);
    CHECK(s->anim_end == s->clips[1].end);
    CHECK_NEAR(s->anim_end, 0.5, 1e-9);
    evr_scene_release(s);
}

/* all: every clip; on node a walk's translation wins, run's scale is the only scale. */
static void test_all(void)
{
    evr_error err;
    evr_scene *s = load("all", &err);
    CHECK(s != NULL);
    if (!s) return;
    check_played(s, "11111");
    CHECK(s->clip_choice == EVR_CLIPS_ALL);
    CHECK(evr_scene_notice(s) == NULL);
    CHECK_NEAR(last_translation(s, "a", 0), 2.0, 1e-6);
    CHECK(s->nodes[node_index(s, "a")].s_curve.num_keys == 2);
    CHECK(s->nodes[node_index(s, "c")].animated);
    CHECK(s->anim_end == s->clips[2].end);
    evr_scene_release(s);
}

static void check_bad(evr_status st, const evr_error *err, const evr_scene *s, const char *has)
{
    CHECK(st == EVR_ERR_ARG);
    CHECK(s == NULL);
    CHECK(strchr(err->msg, '\n') == NULL);
    CHECK(strstr(err->msg, has) != NULL);
    if (!strstr(err->msg, has)) fprintf(stderr, "  message: %s\n", err->msg);
}

static void test_bad(void)
{
    evr_load_options o;
    evr_error err;
    evr_scene *s = NULL;
    evr_status st;
    evr_load_options_defaults(&o);

    o.animation = "nope";
    st = evr_scene_load_with(CLIPS, &o, &s, &err);
    check_bad(st, &err, s, "no animation clip 'nope'");
    CHECK(strstr(err.msg, "0 'walk', 1 'run', 2 'wave', 3 'blink', 4 (unnamed); or all") != NULL);
    o.animation = "5"; /* one past the last */
    st = evr_scene_load_with(CLIPS, &o, &s, &err);
    check_bad(st, &err, s, "no animation clip '5'");
    o.animation = "-1";
    st = evr_scene_load_with(CLIPS, &o, &s, &err);
    check_bad(st, &err, s, "no animation clip '-1'");
    /* a file without clips: a clip named is an error, all is not */
    o.animation = "0";
    st = evr_scene_load_with(EVR_TEST_DATA "/import/plain.gltf", &o, &s, &err);
    check_bad(st, &err, s, "has no animation clips");
    o.animation = "all";
    CHECK_OK(evr_scene_load_with(EVR_TEST_DATA "/import/plain.gltf", &o, &s, &err));
    CHECK(s && s->num_animations == 0 && s->anim_end == 0.0 && !evr_scene_notice(s));
    evr_scene_release(s);
    s = NULL;

    /* the size of the options, as evr_config's */
    o.size = sizeof(size_t);
    o.animation = NULL;
    st = evr_scene_load_with(CLIPS, &o, &s, &err);
    check_bad(st, &err, s, "evr_load_options of");
    evr_load_options_init(&o, sizeof o + 8); /* a newer caller than this library */
    CHECK(o.size == sizeof o + 8 && o.animation == NULL);
    st = evr_scene_load_with(CLIPS, &o, &s, &err);
    check_bad(st, &err, s, "evr_load_options_defaults");
    /* "" and NULL options are the defaults */
    evr_load_options_defaults(&o);
    o.animation = "";
    CHECK_OK(evr_scene_load_with(CLIPS, &o, &s, &err));
    CHECK(s && s->clip_choice == EVR_CLIPS_DEFAULT && evr_scene_notice(s) != NULL);
    evr_scene_release(s);
    CHECK_OK(evr_scene_load_with(CLIPS, NULL, &s, &err));
    CHECK(s && s->clip_choice == EVR_CLIPS_DEFAULT && evr_scene_notice(s) != NULL);
    evr_scene_release(s);
    CHECK(evr_scene_notice(NULL) == NULL);
}

static void test_memory(void)
{
    FILE *f = fopen(CLIPS, "rb");
    unsigned char *b = malloc(1 << 16);
    size_t n = f && b ? fread(b, 1, 1 << 16, f) : 0;
    evr_load_options o;
    evr_scene *s = NULL;
    evr_error err;
    if (f) fclose(f);
    CHECK(n > 0 && n < (1 << 16));
    evr_load_options_defaults(&o);
    o.animation = "run";
    CHECK_OK(evr_scene_load_memory_with(b, n, "gltf", &o, &s, &err));
    if (s) check_played(s, "01000");
    evr_scene_release(s);
    s = NULL;
    CHECK_OK(evr_scene_load_memory(b, n, "gltf", &s, &err));
    if (s) check_played(s, "10101");
    evr_scene_release(s);
    free(b);
}

int main(void)
{
    test_default();
    test_one("run");
    test_one("1");
    test_all();
    test_bad();
    test_memory();
    return check_report("test_clips");
}
