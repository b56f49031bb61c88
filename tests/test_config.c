/* The configuration table (src/config/config_table.c) drives the defaults, option parsing, help and
 * run.json; the format registry (src/io/event_formats.c) lists each format once and --format all
 * writes every one. */
#include "check.h"
#include "config/config_table.h"
#include "evray.h"
#include "evray_experimental.h"
#include "io/event_formats.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The defaults as documented (docs and --help): a wrong default in the table shows up here. */
static void test_documented_defaults(void)
{
    evr_config c;
    evr_config_defaults(&c);
    CHECK(c.width == 346 && c.height == 260);
    CHECK(c.duration == 0.0 && c.start == 0.0 && c.fps == 0.0);
    CHECK(c.samples_per_frame == 0 && evr_config_samples_per_frame(&c) == 10 && c.camera == NULL);
    CHECK(c.pos_thres == 0.2f && c.neg_thres == 0.2f && c.refractory == 0.0f &&
          c.log_floor == 0.02f);
    CHECK(c.sensor == NULL && c.sigma_thres == 0.0f && c.cutoff_hz == 0.0f &&
          c.full_intensity == 1.0f);
    CHECK(c.leak_rate == 0.0f && c.leak_jitter == 0.1f && c.shot_rate == 0.0f);
    CHECK(c.hot_fraction == 0.0f && c.hot_rate == 100.0f && c.time_res == 1e-6 &&
          c.time_jitter == 0.0);
    CHECK(c.ambient == 0.02f && c.seed == 1 && c.threads == 0 && c.backend == EVR_BACKEND_AUTO);
    CHECK(c.gpu_bvh == 0 && c.gpu_event_capacity == 0 && c.no_skip == 0);
    /* refined sampling unless samples per frame are given or GI is on */
    CHECK(c.sampling == EVR_SAMPLING_AUTO && evr_config_sampling(&c) == EVR_SAMPLING_REFINE &&
          c.time_tol == 50e-6 && c.refine_px == 0.5);
    c.samples_per_frame = 10;
    CHECK(evr_config_sampling(&c) == EVR_SAMPLING_UNIFORM);
    c.samples_per_frame = 0;
    c.gi = 1;
    CHECK(evr_config_sampling(&c) == EVR_SAMPLING_UNIFORM);
    c.sampling = EVR_SAMPLING_REFINE;
    CHECK(evr_config_sampling(&c) == EVR_SAMPLING_REFINE);
    evr_config_defaults(&c);
    CHECK(c.adapt_frac == 0.25f && c.min_dt == 20e-6 && c.max_dt == 0.0);
    CHECK(c.out_dir && !strcmp(c.out_dir, "evray-out") && c.formats == EVR_FORMAT_H5);
    CHECK(c.preview_window == 0.05 && c.force == 0);
    CHECK(c.frames_out == NULL && c.frames_fps == 0.0 && c.frames_exposure == 1.0f &&
          c.frames_max == 4.0f);
    CHECK(c.gi == 0 && c.photons == 0 && c.gather_radius == 0.0f && c.gather_max == 0);
    CHECK(c.gather_window == 8 && c.photon_layers == 0 && c.gi_bounces == 4);
}

/* Every row's default is the field's value in evr_config_defaults, and the "(default N)" of its
 * help says the same number. */
static void test_row_defaults(void)
{
    int i, n, fields = 0;
    evr_config c;
    const evr_config_option *t = evr_config_table(&n);
    evr_config_defaults(&c);
    for (i = 0; i < n; i++) {
        const void *f = evr_config_field_const(&c, &t[i]);
        double v = 0.0;
        const char *d;
        if (!f) continue;
        fields++;
        switch (t[i].type) {
        case EVR_OPT_FLAG:
        case EVR_OPT_INT:
        case EVR_OPT_CHOICE: v = *(const int *)f; break;
        case EVR_OPT_INT64: v = (double)*(const int64_t *)f; break;
        case EVR_OPT_U32: v = *(const uint32_t *)f; break;
        case EVR_OPT_U64: v = (double)*(const uint64_t *)f; break;
        case EVR_OPT_FLOAT:
            v = *(const float *)f;
            CHECK(*(const float *)f == (float)t[i].def);
            break;
        case EVR_OPT_DOUBLE: v = *(const double *)f; break;
        case EVR_OPT_STRING: {
            const char *s = *(const char *const *)f;
            CHECK((s == NULL) == (t[i].def_text == NULL));
            if (s && t[i].def_text) CHECK(!strcmp(s, t[i].def_text));
            continue;
        }
        default: break;
        }
        if (t[i].type != EVR_OPT_FLOAT && v != t[i].def) {
            fprintf(stderr, "row %s: default %g, evr_config_defaults %g\n", t[i].name, t[i].def, v);
            CHECK(0);
        }
        if (t[i].help && (d = strstr(t[i].help, "(default ")) != NULL) {
            char *end;
            double h = strtod(d + 9, &end);
            if (end != d + 9 && (*end == ')' || *end == ':' || *end == ';')) {
                if (!((float)h == (float)t[i].def))
                    fprintf(stderr, "row %s: help says default %g, table %g\n", t[i].name, h,
                            t[i].def);
                CHECK((float)h == (float)t[i].def);
            }
        }
    }
    CHECK(fields >= 48); /* every field of evr_config has its row */
}

/* Names, options, JSON keys and ranks are unique; ranks run 1..N without a gap. */
static void test_table_shape(void)
{
    int i, k, n, ranks = 0;
    const evr_config_option *t = evr_config_table(&n);
    for (i = 0; i < n; i++) {
        if (t[i].json_rank > 0) ranks++;
        CHECK(!t[i].json == !t[i].json_rank);
        for (k = i + 1; k < n; k++) {
            CHECK(strcmp(t[i].name, t[k].name));
            if (t[i].flag && t[k].flag) CHECK(strcmp(t[i].flag, t[k].flag));
            if (t[i].json && t[k].json)
                CHECK(strcmp(t[i].json, t[k].json) && t[i].json_rank != t[k].json_rank);
            if (t[i].type != EVR_OPT_NONE && t[k].type != EVR_OPT_NONE)
                CHECK(t[i].offset != t[k].offset);
        }
    }
    for (i = 0; i < n; i++) CHECK(t[i].json_rank <= ranks);
}

/* Sets option flag to text on the defaults and checks that the bytes of field (size bytes at
 * offset) changed and no others did. */
static void check_sets(const char *flag, const char *text, size_t offset, size_t size)
{
    evr_config a, b;
    evr_error err = {{0}};
    const char *name;
    size_t k;
    const evr_config_option *o = evr_config_option_find(flag, &name);
    evr_config_defaults(&a);
    memcpy(&b, &a, sizeof a);
    CHECK(o != NULL);
    if (!o) return;
    if (evr_config_option_set(&b, o, evr_config_option_takes_value(o) ? text : NULL, &err) !=
        EVR_OK) {
        fprintf(stderr, "%s %s: %s\n", flag, text, err.msg);
        CHECK(0);
        return;
    }
    CHECK(memcmp((char *)&a + offset, (char *)&b + offset, size) != 0);
    for (k = 0; k < sizeof a; k++)
        if (k < offset || k >= offset + size)
            if (((unsigned char *)&a)[k] != ((unsigned char *)&b)[k]) {
                fprintf(stderr, "%s %s changed byte %zu outside its field\n", flag, text, k);
                CHECK(0);
                break;
            }
}

static size_t type_size(evr_opt_type t)
{
    switch (t) {
    case EVR_OPT_FLAG:
    case EVR_OPT_INT:
    case EVR_OPT_CHOICE: return sizeof(int);
    case EVR_OPT_INT64: return sizeof(int64_t);
    case EVR_OPT_U32: return sizeof(uint32_t);
    case EVR_OPT_U64: return sizeof(uint64_t);
    case EVR_OPT_FLOAT: return sizeof(float);
    case EVR_OPT_DOUBLE: return sizeof(double);
    case EVR_OPT_STRING: return sizeof(const char *);
    default: return 0;
    }
}

/* Every option with a field of its own sets that field and nothing else. */
static void test_options_set_their_field(void)
{
    int i, n;
    const evr_config_option *t = evr_config_table(&n);
    for (i = 0; i < n; i++) {
        const char *text = "3";
        const evr_opt_choice *ch;
        if (!t[i].flag || t[i].type == EVR_OPT_NONE) continue;
        if (t[i].type == EVR_OPT_FLOAT || t[i].type == EVR_OPT_DOUBLE) text = "0.5";
        if (t[i].type == EVR_OPT_STRING) text = "elsewhere";
        if (!strcmp(t[i].name, "sensor")) text = "davis346";
        if (!strcmp(t[i].name, "formats")) text = "txt";
        if (!strcmp(t[i].name, "time_res")) text = "2e-6";
        if (!strcmp(t[i].name, "min_dt")) text = "1e-4";
        if (!strcmp(t[i].name, "refine_px")) text = "0.25";
        if (t[i].type == EVR_OPT_CHOICE) /* a name other than the default's */
            for (ch = t[i].choices; ch->name || ch->json; ch++)
                if (ch->name && !ch->refuse && ch->value != (int)t[i].def) {
                    text = ch->name;
                    break;
                }
        check_sets(t[i].flag, text, t[i].offset, type_size(t[i].type));
        if (t[i].alias) check_sets(t[i].alias, text, t[i].offset, type_size(t[i].type));
    }
}

/* The options that set other fields, and the checks of values as given. */
static void test_special_options(void)
{
    evr_config c;
    evr_error err = {{0}};
    const char *name;
    evr_config_defaults(&c);
    CHECK_OK(
        evr_config_option_set(&c, evr_config_option_find("--res=640x480", &name), "640x480", &err));
    CHECK(c.width == 640 && c.height == 480 && !strcmp(name, "--res"));
    CHECK_OK(evr_config_option_set(&c, evr_config_option_find("--thres", &name), "0.3", &err));
    CHECK(c.pos_thres == 0.3f && c.neg_thres == 0.3f);
    CHECK(c.preview == EVR_PREVIEW_VIDEO);
    CHECK_OK(evr_config_option_set(&c, evr_config_option_find("--no-preview", &name), NULL, &err));
    CHECK(c.preview == EVR_PREVIEW_NONE);
    CHECK_OK(evr_config_option_set(&c, evr_config_option_find("--preview", &name), "png", &err));
    CHECK(c.preview == EVR_PREVIEW_PNG);
    CHECK(evr_config_option_set(&c, evr_config_option_find("--preview", &name), "mp4", &err) ==
          EVR_ERR_ARG);
    CHECK_OK(evr_config_option_set(&c, evr_config_option_find("--format", &name), "all", &err));
    CHECK(c.formats == evr_event_formats_all());
    CHECK_OK(evr_config_option_set(&c, evr_config_option_find("--gpu-event-capacity", &name),
                                   "99999999999999", &err));
    CHECK(c.gpu_event_capacity == ((int64_t)1 << 40));
    CHECK(evr_config_option_find("--force=1", &name) == NULL); /* no value taken */
    CHECK(evr_config_option_find("--threadsx", &name) == NULL);
    CHECK(evr_config_option_find("-o", &name) != NULL && !strcmp(name, "-o"));
    CHECK(evr_config_option_set(&c, evr_config_option_find("--duration", &name), "0", &err) ==
          EVR_ERR_ARG);
    CHECK(strstr(err.msg, "--duration must be a positive number of seconds") != NULL);
    CHECK(evr_config_option_set(&c, evr_config_option_find("--photons", &name), "4294967297",
                                &err) == EVR_ERR_ARG);
    CHECK(evr_config_option_set(&c, evr_config_option_find("--gi", &name), "path", &err) ==
          EVR_ERR_ARG);
    CHECK(strstr(err.msg, "evray still") != NULL);
    CHECK(evr_config_option_set(&c, evr_config_option_find("--backend", &name), "gpu", &err) ==
          EVR_ERR_ARG);
    CHECK(!strcmp(err.msg, "--backend: unknown backend 'gpu' (auto, cpu, cuda)"));
    CHECK(evr_config_option_set(&c, evr_config_option_find("--sensor", &name), "davis999", &err) ==
          EVR_ERR_ARG);
    /* the library's checks come from the same rows */
    evr_config_defaults(&c);
    c.samples_per_frame = -1;
    CHECK(evr_config_validate(&c, NULL, &err) == EVR_ERR_ARG &&
          strstr(err.msg, "samples per frame") != NULL);
    evr_config_defaults(&c);
    c.gi = 1;
    c.photon_layers = 4097;
    CHECK(evr_config_validate(&c, NULL, &err) == EVR_ERR_ARG &&
          strstr(err.msg, "--photon-layers") != NULL);
    c.gi = 0; /* GI settings are checked only with GI on */
    CHECK_OK(evr_config_validate(&c, NULL, &err));
}

/* Each format is listed once, by name, alias and file; "all" selects every one. */
static void test_format_registry(void)
{
    int i, k, n, bits;
    evr_error err = {{0}};
    const evr_event_format *const *f = evr_event_formats(&n);
    CHECK(n >= 3);
    for (i = 0; i < n; i++) {
        CHECK(f[i]->name && f[i]->file && f[i]->open && f[i]->help);
        CHECK(evr_format_name(i) == f[i]->name && evr_format_file(i) == f[i]->file);
        for (k = i + 1; k < n; k++) {
            CHECK(strcmp(f[i]->name, f[k]->name) && strcmp(f[i]->file, f[k]->file));
            if (f[k]->alias) CHECK(strcmp(f[i]->name, f[k]->alias));
        }
        CHECK_OK(evr_formats_parse("--format", f[i]->name, &bits, &err));
        CHECK(bits == 1 << i);
    }
    CHECK(evr_format_name(n) == NULL && evr_format_file(n) == NULL);
    CHECK(EVR_FORMAT_H5 == 1 << 0 && !strcmp(f[0]->name, "h5"));
    CHECK(EVR_FORMAT_TXT == 1 << 1 && !strcmp(f[1]->name, "txt"));
    CHECK(EVR_FORMAT_NPY == 1 << 2 && !strcmp(f[2]->name, "npy"));
    CHECK_OK(evr_formats_parse("--format", "all", &bits, &err));
    CHECK(bits == (1 << n) - 1);
    CHECK(evr_formats_parse("--format", "avi", &bits, &err) == EVR_ERR_ARG);
}

/* A run with every format writes every format's file. */
static void test_all_formats_written(void)
{
    char dir[] = "/tmp/evr-test-config-XXXXXX", p[512];
    evr_scene *scene = NULL;
    evr_sim *sim = NULL;
    evr_config c;
    evr_error err = {{0}};
    int i, n;
    struct stat sb;
    const evr_event_format *const *f = evr_event_formats(&n);
    CHECK(mkdtemp(dir) != NULL);
    CHECK_OK(evr_demo_load("square", &scene, &err));
    if (!scene) return;
    evr_config_defaults(&c);
    c.width = 32;
    c.height = 24;
    c.duration = 0.05;
    c.backend = EVR_BACKEND_CPU;
    c.preview_window = 0.0;
    c.out_dir = dir;
    c.force = 1;
    c.formats = evr_event_formats_all();
    CHECK_OK(evr_sim_new(scene, &c, &sim, &err));
    if (sim) CHECK_OK(evr_sim_run(sim, NULL, NULL, &err));
    evr_sim_release(sim);
    for (i = 0; i < n; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, f[i]->file);
        CHECK(stat(p, &sb) == 0 && sb.st_size > 0);
        remove(p);
    }
    snprintf(p, sizeof p, "%s/run.json", dir);
    remove(p);
    rmdir(dir);
    evr_scene_release(scene);
}

/* The size field: set by evr_config_defaults, and a size the library does not know is refused. */
static void test_size_field(void)
{
    evr_config c;
    evr_error err = {{0}};
    evr_sim *sim = NULL;
    evr_config_defaults(&c);
    CHECK(c.size == sizeof c);
    CHECK_OK(evr_config_validate(&c, NULL, &err));
    c.size = sizeof c - 8;
    CHECK(evr_config_validate(&c, NULL, &err) == EVR_ERR_ARG &&
          strstr(err.msg, "evr_config_defaults") != NULL);
    c.size = sizeof c + 8;
    CHECK(evr_config_validate(&c, NULL, &err) == EVR_ERR_ARG);
    c.size = 0;
    CHECK(evr_sim_new(NULL, &c, &sim, &err) == EVR_ERR_ARG && sim == NULL);
}

int main(void)
{
    test_size_field();
    test_documented_defaults();
    test_row_defaults();
    test_table_shape();
    test_options_set_their_field();
    test_special_options();
    test_format_registry();
    test_all_formats_written();
    return check_report("test_config");
}
