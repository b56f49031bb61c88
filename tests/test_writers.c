/* Event writers (HDF5, text, NPY, Prophesee EVT 2.0, EVT 3.0, DAT, ROS1 bag; AEDAT 4.0 is
 * tests/test_aedat4.c's, benchmarked here too), the event reader, the JSON builder and the
 * preview images.
 * Python (h5py, numpy) reads the files as an independent check when it is installed. */
#include <dirent.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <bzlib.h>
#include <lz4frame.h>
#include <stb/stb_image.h>
#include <zlib.h>

#include "check.h"
#include "evray.h"
#include "io/chunk_compress.h"
#include "io/deflate_runs.h"
#include "par_pool.h"
#include "io/event_reader.h"
#include "io/event_writer.h"
#include "io/file_commit.h"
#include "io/file_room.h"
#include "io/json.h"
#include "io/json_read.h"
#include "io/par_pack.h"
#include "io/preview.h"

#define W 640
#define H 480

typedef evr_status (*open_fn)(const char *, const evr_writer_meta *, evr_event_writer **,
                              evr_error *);

static const struct {
    const char *ext;
    open_fn open;
    int stores_size;
    /* a flush leaves the events of the last partial chunk of this many in memory (0: none) */
    size_t chunk;
} formats[] = {
    {"h5", evr_h5_writer_open, 1, 65536},
    {"txt", evr_txt_writer_open, 0, 0},
    {"npy", evr_npy_writer_open, 0, 0},
};
#define NFORMATS (sizeof formats / sizeof formats[0])

static uint64_t rng_next(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 33;
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static int dir_entries(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    if (!d) return -1;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
    closedir(d);
    return n;
}

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    char p[1024];
    if (!d) return;
    while ((e = readdir(d))) {
        struct stat st;
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        if (stat(p, &st) == 0 && S_ISDIR(st.st_mode)) remove_tree(p);
        else remove(p);
    }
    closedir(d);
    rmdir(dir);
}

static int copy_file(const char *from, const char *to)
{
    FILE *a = fopen(from, "rb"), *b = a ? fopen(to, "wb") : NULL;
    char buf[65536];
    size_t n;
    int ok = a && b;
    while (ok && (n = fread(buf, 1, sizeof buf, a)) > 0) ok = fwrite(buf, 1, n, b) == n;
    if (a) fclose(a);
    if (b && fclose(b) != 0) ok = 0;
    return ok;
}

/* Sorted events with runs of equal timestamps, events on exact millisecond boundaries, gaps of
 * several empty milliseconds, and extreme coordinates. */
static evr_event *make_events(size_t n, int64_t *last_t)
{
    evr_event *ev = calloc(n, sizeof *ev);
    uint64_t s = 12345;
    int64_t t = 0;
    for (size_t i = 0; i < n; i++) {
        uint64_t r = rng_next(&s) % 100;
        if (i > 0) {
            if (r < 30) t += 0;                               /* same timestamp */
            else if (r < 45) t = (t / 1000 + 1) * 1000;       /* next millisecond boundary */
            else if (r < 48) t = (t / 1000 + 4) * 1000 + 999; /* skip empty milliseconds */
            else t += (int64_t)(rng_next(&s) % 300) + 1;
        }
        ev[i].t = t;
        ev[i].x = (uint16_t)(rng_next(&s) % W);
        ev[i].y = (uint16_t)(rng_next(&s) % H);
        ev[i].p = (int8_t)(rng_next(&s) & 1);
    }
    ev[n / 2].x = 65535;
    ev[n / 2].y = 65535;
    ev[n / 3].x = 0;
    ev[n / 3].y = 0;
    *last_t = t;
    return ev;
}

static int same_events(const evr_event *a, const evr_event *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (a[i].t != b[i].t || a[i].x != b[i].x || a[i].y != b[i].y || a[i].p != b[i].p) {
            fprintf(stderr, "event %zu differs: %lld %u %u %d vs %lld %u %u %d\n", i,
                    (long long)a[i].t, a[i].x, a[i].y, a[i].p, (long long)b[i].t, b[i].x, b[i].y,
                    b[i].p);
            return 0;
        }
    return 1;
}

static char *make_config(void)
{
    evr_json j;
    evr_json_init(&j, 1);
    evr_json_begin_object(&j);
    evr_json_key(&j, "width");
    evr_json_integer(&j, W);
    evr_json_key(&j, "height");
    evr_json_integer(&j, H);
    evr_json_key(&j, "scene");
    evr_json_string(&j, "demo \"spheres\"");
    evr_json_key(&j, "pos_thres");
    evr_json_float(&j, 0.2f);
    evr_json_end_object(&j);
    return evr_json_take(&j);
}

/* Writes the events in uneven segments (one empty) through one writer, checking along the way
 * that the temporary file is readable after each flush, then reads the result back. */
static void test_format(const char *dir, size_t f, const evr_event *ev, size_t n,
                        int64_t duration_us, const char *config)
{
    char path[512], tmp[600], partial[600];
    evr_writer_meta meta = {0};
    evr_event_writer *w = NULL;
    evr_error err;
    evr_status st;
    size_t at = 0, seg = 0;
    int checked_partial = 0;

    meta.width = W;
    meta.height = H;
    meta.config_json = config;
    meta.max_t_us = duration_us + 1; /* every event before it: the HDF5 writer's t is uint32 */
    snprintf(path, sizeof path, "%s/events.%s", dir, formats[f].ext);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    snprintf(partial, sizeof partial, "%s/partial.%s", dir, formats[f].ext);
    st = formats[f].open(path, &meta, &w, &err);
    CHECK(st == EVR_OK);
    if (st != EVR_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return;
    }
    CHECK(file_exists(tmp));
    for (;;) {
        size_t len = seg == 3 ? 0 : (seg * 397 + 11) % 1500; /* segment 3 is empty */
        if (len > n - at) len = n - at;
        st = w->write(w, ev + at, len, &err);
        CHECK(st == EVR_OK);
        st = w->flush(w, &err);
        CHECK(st == EVR_OK);
        at += len;
        seg++;
        CHECK(!file_exists(path));
        /* a killed run keeps every flushed event (HDF5: but those of its last partial chunk):
         * read a copy of the temporary file */
        if (at > 0 && at > n / 2 && !checked_partial) {
            evr_event *got = NULL;
            size_t ngot = 0, kept = formats[f].chunk ? at - at % formats[f].chunk : at;
            checked_partial = 1;
            CHECK(copy_file(tmp, partial));
            st = evr_events_read(partial, &got, &ngot, NULL, NULL, &err);
            CHECK(st == EVR_OK);
            if (st != EVR_OK) fprintf(stderr, "%s\n", err.msg);
            CHECK(ngot == kept);
            if (st == EVR_OK && ngot == kept) CHECK(same_events(got, ev, kept));
            free(got);
            remove(partial);
        }
        if (at == n && seg >= 5) break;
    }
    CHECK(seg > 4);
    /* out-of-order events are refused */
    if (n > 0) {
        evr_event early = ev[0];
        early.t = ev[n - 1].t - 1;
        if (early.t < ev[n - 1].t) {
            st = w->write(w, &early, 1, &err);
            CHECK(st == EVR_ERR_ARG);
        }
    }
    st = w->finish(w, duration_us, &err);
    CHECK(st == EVR_OK);
    if (st != EVR_OK) fprintf(stderr, "%s\n", err.msg);
    CHECK(file_exists(path));
    CHECK(!file_exists(tmp));

    {
        evr_event *got = NULL;
        size_t ngot = 0;
        int width = 0, height = 0;
        st = evr_events_read(path, &got, &ngot, &width, &height, &err);
        CHECK(st == EVR_OK);
        if (st != EVR_OK) fprintf(stderr, "%s\n", err.msg);
        CHECK(ngot == n);
        if (st == EVR_OK && ngot == n) CHECK(same_events(got, ev, n));
        CHECK(width == (formats[f].stores_size ? W : -1));
        CHECK(height == (formats[f].stores_size ? H : -1));
        free(got);
    }
}

/* ms_to_idx[i] = first event with t >= i ms, i = 0 .. ceil(duration / 1 ms). */
static void check_ms_to_idx(const char *path, const evr_event *ev, size_t n, int64_t duration_us)
{
    uint64_t *idx = NULL;
    size_t nidx = 0, expect_n = (size_t)((duration_us + 999) / 1000) + 1, bad = 0;
    evr_error err;
    evr_status st = evr_h5_read_ms_to_idx(path, &idx, &nidx, &err);
    CHECK(st == EVR_OK);
    if (st != EVR_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return;
    }
    CHECK(nidx == expect_n);
    for (size_t i = 0, k = 0; i < nidx; i++) {
        while (k < n && ev[k].t < (int64_t)i * 1000) k++;
        if (idx[i] != k) bad++;
    }
    CHECK(bad == 0);
    /* entries past the last event hold the count */
    if (nidx && (n == 0 || ev[n - 1].t < (int64_t)(nidx - 1) * 1000)) CHECK(idx[nidx - 1] == n);
    free(idx);
}

/* The HDF5 writer stores its event chunks itself (compressed in parallel, H5Dwrite_chunk): more
 * than five chunks of events in uneven batches, flushes with a partial chunk staged, a flush on a
 * chunk boundary, flushes with nothing new, one batch larger than the
 * writer's stage on small machines; the temporary file is read after a flush, the result after
 * finish. Python compares its chunks with those HDF5's own filter pipeline makes. */
static const size_t large_n = 400000;

static void test_h5_large(const char *root)
{
    static const struct {
        size_t len;
        int flush;
    } steps[] = {
        {1, 1}, {65535, 1}, {0, 1}, {0, 1}, {3, 0}, {300000, 1}, {7, 0}, {20000, 1}, {14454, 1},
    };
    evr_writer_meta meta = {.width = W,
                            .height = H,
                            .config_json = "{}",
                            .max_t_us = 0}; /* no bound on the timestamps: t is int64 */
    evr_event_writer *w = NULL;
    evr_event *ev, *got = NULL;
    int64_t last_t;
    size_t at = 0, ngot = 0;
    char dir[512], path[600], tmp[620], partial[600];
    evr_error err;
    evr_status st;

    ev = make_events(large_n, &last_t);
    CHECK(ev != NULL);
    if (!ev) return;
    snprintf(dir, sizeof dir, "%s/large", root);
    CHECK(mkdir(dir, 0700) == 0);
    snprintf(path, sizeof path, "%s/events.h5", dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    snprintf(partial, sizeof partial, "%s/partial.h5", root);
    CHECK_OK(evr_h5_writer_open(path, &meta, &w, &e_));
    if (!w) {
        free(ev);
        return;
    }
    for (size_t s = 0; s < sizeof steps / sizeof steps[0]; s++) {
        CHECK(at + steps[s].len <= large_n);
        CHECK_OK(w->write(w, ev + at, steps[s].len, &e_));
        at += steps[s].len;
        if (!steps[s].flush) continue;
        CHECK_OK(w->flush(w, &e_));
        /* after the big batch: what a killed run would leave (its full chunks: the last
         * partial one stays in memory, so that when flushes come changes no byte of the file) */
        if (steps[s].len == 300000) {
            const size_t kept = at - at % 65536;
            CHECK(copy_file(tmp, partial));
            st = evr_events_read(partial, &got, &ngot, NULL, NULL, &err);
            CHECK(st == EVR_OK);
            if (st != EVR_OK) fprintf(stderr, "%s\n", err.msg);
            CHECK(ngot == kept && kept == 5 * 65536);
            if (st == EVR_OK && ngot == kept) CHECK(same_events(got, ev, kept));
            free(got);
            got = NULL;
            remove(partial);
        }
    }
    CHECK(at == large_n);
    st = w->finish(w, last_t + 1, &err);
    CHECK(st == EVR_OK);
    if (st != EVR_OK) fprintf(stderr, "%s\n", err.msg);
    st = evr_events_read(path, &got, &ngot, NULL, NULL, &err);
    CHECK(st == EVR_OK);
    if (st != EVR_OK) fprintf(stderr, "%s\n", err.msg);
    CHECK(ngot == large_n);
    if (st == EVR_OK && ngot == large_n) CHECK(same_events(got, ev, large_n));
    free(got);
    check_ms_to_idx(path, ev, large_n, last_t + 1);
    free(ev);
}

/* events/t: uint32 when the writer is told every timestamp stays below 2^32 us (an event past
 * it is an error, not wrapped), int64 otherwise (a timestamp past 2^32 us reads back whole). */
static void test_h5_t_range(const char *root)
{
    char path[600];
    evr_event ev[3] = {
        {1000, 1, 2, 1, 0}, {2000, 3, 4, 0, 0}, {(int64_t)UINT32_MAX + 5, 5, 6, 1, 0}};
    evr_error err;
    evr_event_writer *w = NULL;
    evr_writer_meta meta = {.width = W, .height = H, .config_json = "{}", .max_t_us = 3000};
    snprintf(path, sizeof path, "%s/t32.h5", root);
    CHECK_OK(evr_h5_writer_open(path, &meta, &w, &err));
    if (w) {
        err.msg[0] = 0;
        CHECK(w->write(w, ev, 3, &err) == EVR_ERR_ARG && strstr(err.msg, "uint32") != NULL);
        w->abort(w);
    }
    meta.max_t_us = (int64_t)UINT32_MAX + 10;
    snprintf(path, sizeof path, "%s/t64.h5", root);
    CHECK_OK(evr_h5_writer_open(path, &meta, &w, &err));
    if (w) {
        CHECK_OK(w->write(w, ev, 3, &err));
        CHECK_OK(w->finish(w, ev[2].t + 1, &err));
        evr_event *got = NULL;
        size_t n = 0;
        int gw, gh;
        CHECK_OK(evr_events_read(path, &got, &n, &gw, &gh, &err));
        CHECK(n == 3 && got && got[2].t == ev[2].t && got[0].t == 1000 && got[1].x == 3);
        free(got);
    }
}

/* The NPY writer packs and writes large writes in parts on its pool (pwrite at each part's place):
 * large and small writes and flushes interleaved read back whole, the temporary file after a flush
 * holds every event so far, and an event out of order inside a large write is refused with the
 * events before it kept (the finished file holds exactly those). */
static void test_npy_large(const char *root)
{
    static const struct {
        size_t len;
        int flush;
    } steps[] = {
        {1, 1}, {65535, 0}, {3, 1}, {300000, 1}, {7, 0}, {33000, 0}, {1454, 1},
    };
    const size_t n = 400000;
    int64_t last_t;
    evr_event *ev = make_events(n, &last_t), *got = NULL;
    evr_writer_meta meta = {.width = W, .height = H, .config_json = "{}", .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_error err;
    size_t at = 0, ngot = 0;
    char path[600], tmp[620], partial[600];
    CHECK(ev != NULL);
    if (!ev) return;
    snprintf(path, sizeof path, "%s/large.npy", root);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    snprintf(partial, sizeof partial, "%s/partial.npy", root);
    CHECK_OK(evr_npy_writer_open(path, &meta, &w, &err));
    for (size_t s = 0; w && s < sizeof steps / sizeof steps[0]; s++) {
        CHECK_OK(w->write(w, ev + at, steps[s].len, &err));
        at += steps[s].len;
        if (!steps[s].flush) continue;
        CHECK_OK(w->flush(w, &err));
        CHECK(copy_file(tmp, partial));
        CHECK_OK(evr_events_read(partial, &got, &ngot, NULL, NULL, &err));
        CHECK(ngot == at);
        if (got && ngot == at) CHECK(same_events(got, ev, at));
        free(got);
        got = NULL;
        remove(partial);
    }
    CHECK(at == n);
    if (w) {
        CHECK_OK(w->finish(w, last_t + 1, &err));
        CHECK_OK(evr_events_read(path, &got, &ngot, NULL, NULL, &err));
        CHECK(ngot == n);
        if (got && ngot == n) CHECK(same_events(got, ev, n));
        free(got);
        got = NULL;
    }
    /* refused inside a large write, after a small one */
    {
        const size_t k = 70001;
        CHECK(ev[k - 1].t > 0);
        ev[k].t = ev[k - 1].t - 1;
        snprintf(path, sizeof path, "%s/refused.npy", root);
        CHECK_OK(evr_npy_writer_open(path, &meta, &w, &err));
        if (w) {
            CHECK_OK(w->write(w, ev, 5, &err));
            err.msg[0] = 0;
            CHECK(w->write(w, ev + 5, 100000, &err) == EVR_ERR_ARG &&
                  strstr(err.msg, "out of time order") != NULL);
            CHECK_OK(w->finish(w, ev[k - 1].t + 1, &err));
            CHECK_OK(evr_events_read(path, &got, &ngot, NULL, NULL, &err));
            CHECK(ngot == k);
            if (got && ngot == k) CHECK(same_events(got, ev, k));
            free(got);
        }
    }
    free(ev);
}

/* A batch large enough to be staged on the writer's pool, with one event it must refuse (out of
 * time order; past events/t's uint32 range): the write says why, the events before it are kept
 * and the finished file holds exactly those, with their ms_to_idx. */
static void test_h5_refused_in_bulk(const char *root)
{
    const size_t n = 100000, bad_at[2] = {70001, 50003};
    for (int kind = 0; kind < 2; kind++) {
        int64_t last_t;
        evr_event *ev = make_events(n, &last_t), *got = NULL;
        evr_writer_meta meta = {
            .width = W, .height = H, .config_json = "{}", .max_t_us = kind == 0 ? 0 : last_t + 10};
        evr_event_writer *w = NULL;
        evr_error err;
        size_t ngot = 0, k = bad_at[kind];
        char path[600];
        CHECK(ev != NULL);
        if (!ev) return;
        CHECK(ev[k - 1].t > 0);
        ev[k].t = kind == 0 ? ev[k - 1].t - 1 : (int64_t)UINT32_MAX + 1;
        snprintf(path, sizeof path, "%s/refused%d.h5", root, kind);
        CHECK_OK(evr_h5_writer_open(path, &meta, &w, &err));
        if (w) {
            err.msg[0] = 0;
            CHECK(w->write(w, ev, n, &err) == EVR_ERR_ARG);
            CHECK(strstr(err.msg, kind == 0 ? "out of time order" : "uint32") != NULL);
            CHECK_OK(w->finish(w, ev[k - 1].t + 1, &err));
            CHECK_OK(evr_events_read(path, &got, &ngot, NULL, NULL, &err));
            CHECK(ngot == k);
            if (got && ngot == k) CHECK(same_events(got, ev, k));
            free(got);
            check_ms_to_idx(path, ev, k, ev[k - 1].t + 1);
        }
        free(ev);
    }
}

/* Raw-inflates src (n bytes) into out (room bytes); returns the length, or (size_t)-1. */
static size_t raw_inflate(const unsigned char *src, size_t n, unsigned char *out, size_t room)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, -15) != Z_OK) return (size_t)-1;
    z.next_in = (unsigned char *)src;
    z.avail_in = (uInt)n;
    z.next_out = out;
    z.avail_out = (uInt)room;
    const int r = inflate(&z, Z_FINISH);
    const size_t len = z.total_out;
    inflateEnd(&z);
    return r == Z_STREAM_END ? len : (size_t)-1;
}

/* Blocks of runs inflate to their input: runs of every length around the match limits (3, 258),
 * bytes of both literal code lengths (8 and 9 bits), random bytes, an empty input; too little
 * room is refused, not overrun. */
static void test_deflate_runs(void)
{
    static const size_t runs[] = {1,   2,   3,   4,   10,  257,  258,  259,
                                  260, 261, 515, 516, 517, 1000, 65536};
    enum { N = 200000 };
    unsigned char *src = malloc(N), *dst = malloc(2 * N), *back = malloc(N);
    uint64_t s = 7;
    CHECK(src && dst && back);
    if (!src || !dst || !back) goto done;
    for (int kind = 0; kind < 3; kind++) {
        size_t n = 0, k = 0;
        while (n < N) {
            size_t len = kind == 2 ? 1 : runs[k++ % (sizeof runs / sizeof runs[0])];
            unsigned char b =
                (unsigned char)(kind == 0 ? (k * 37) : rng_next(&s)); /* both sides of 144 */
            for (size_t i = 0; i < len && n < N; i++) src[n++] = b;
        }
        size_t z = evr_deflate_runs(src, n, dst, 2 * N);
        CHECK(z > 0);
        CHECK(raw_inflate(dst, z, back, N) == n && memcmp(back, src, n) == 0);
        if (kind == 0) CHECK(z < n / 10);                 /* runs shrink */
        CHECK(evr_deflate_runs(src, n, dst, z - 1) == 0); /* one byte short */
    }
    size_t z = evr_deflate_runs(src, 0, dst, 16);
    CHECK(z > 0 && raw_inflate(dst, z, back, N) == 0);
    src[0] = 200;
    z = evr_deflate_runs(src, 1, dst, 16);
    CHECK(z > 0 && raw_inflate(dst, z, back, N) == 1 && back[0] == 200);
    CHECK(evr_deflate_repeats((const unsigned char *)"aaab", 4) == 2);
done:
    free(src);
    free(dst);
    free(back);
}

/* A stored plane larger than one stored block (65,535 bytes) before a compressed one: the
 * stream inflates to the shuffled chunk. */
static void test_chunk_stored_blocks(void)
{
    enum { CE = 70000 };
    uint16_t *v = malloc(sizeof(uint16_t) * CE);
    unsigned char *raw = malloc((size_t)CE * 2);
    evr_chunk_worker *w = evr_chunk_worker_new((size_t)CE * 2);
    size_t bound = evr_chunk_bound((size_t)CE * 2);
    unsigned char *dst = malloc(bound);
    uint64_t s = 99;
    CHECK(v && raw && w && dst);
    if (!v || !raw || !w || !dst) goto done;
    for (size_t i = 0; i < CE; i++)
        v[i] = (uint16_t)((rng_next(&s) & 0xff) | (i % 3) << 8); /* random low, plain high byte */
    evr_chunk_job j;
    memset(&j, 0, sizeof j);
    j.src = v;
    j.stride = sizeof(uint16_t);
    j.elem_size = 2;
    j.count = CE - 5; /* zero padded */
    j.chunk_elems = CE;
    j.level = 1;
    j.dst = dst;
    CHECK(evr_chunk_compress(&j, w));
    CHECK(j.dst_size > CE &&
          j.dst_size < (size_t)CE + CE / 4); /* low plane stored, high plane compressed */
    CHECK(dst[2] == 0x00 && dst[3] == 0xff && dst[4] == 0xff && dst[5] == 0x00 &&
          dst[6] == 0x00); /* 65,535 bytes */
    uLongf len = (uLongf)CE * 2;
    CHECK(uncompress(raw, &len, dst, (uLong)j.dst_size) == Z_OK && len == (uLongf)CE * 2);
    size_t bad = 0;
    for (size_t i = 0; i < CE; i++) {
        const uint16_t want = i < j.count ? v[i] : 0;
        if (raw[i] != (want & 0xff) || raw[CE + i] != (want >> 8)) bad++;
    }
    CHECK(bad == 0);
done:
    free(v);
    free(raw);
    evr_chunk_worker_free(w);
    free(dst);
}

/* The reader (io/json_read.h) takes back what the writer writes, and refuses what is not JSON. */
static void test_json_read(void)
{
    evr_json j;
    evr_jdoc d;
    char *text, buf[64];
    int root, a, c, k;
    static const char *bad[] = {"",    "{", "[1,]", "{\"a\" 1}", "{\"a\":}",
                                "tru", "-", "1e",   "\"open",    "[1 2]"};

    evr_json_init(&j, 1);
    evr_json_begin_object(&j);
    evr_json_key(&j, "s");
    evr_json_string(&j, "q\"b\\n\nt\tc\x01"
                        "e\xc3\xa9");
    evr_json_key(&j, "a");
    evr_json_begin_array(&j);
    evr_json_integer(&j, -12);
    evr_json_number(&j, 0.1);
    evr_json_float(&j, 1e-7f);
    evr_json_boolean(&j, 1);
    evr_json_null(&j);
    evr_json_begin_object(&j);
    evr_json_end_object(&j);
    evr_json_end_array(&j);
    evr_json_key(&j, "k\"ey");
    evr_json_integer(&j, 7);
    evr_json_end_object(&j);
    text = evr_json_take(&j);
    CHECK(text != NULL);
    if (!text) return;
    root = evr_jdoc_parse(&d, text, strlen(text));
    CHECK(root >= 0 && evr_jdoc_type(&d, root) == EVR_JDOC_OBJECT);
    CHECK(evr_jdoc_string(&d, evr_jdoc_get(&d, root, "s"), buf, sizeof buf) &&
          !strcmp(buf, "q\"b\\n\nt\tc\x01"
                       "e\xc3\xa9"));
    a = evr_jdoc_get(&d, root, "a");
    CHECK(evr_jdoc_count(&d, a) == 6);
    c = evr_jdoc_first(&d, a);
    CHECK(evr_jdoc_number(&d, c, 0) == -12.0);
    c = evr_jdoc_next(&d, c);
    CHECK(fabs(evr_jdoc_number(&d, c, 0) - 0.1) < 1e-15);
    c = evr_jdoc_next(&d, c);
    CHECK((float)evr_jdoc_number(&d, c, 0) == 1e-7f);
    c = evr_jdoc_next(&d, c);
    CHECK(evr_jdoc_type(&d, c) == EVR_JDOC_BOOL);
    c = evr_jdoc_next(&d, c);
    CHECK(evr_jdoc_type(&d, c) == EVR_JDOC_NULL && evr_jdoc_number(&d, c, 5.0) == 5.0);
    c = evr_jdoc_next(&d, c);
    CHECK(evr_jdoc_type(&d, c) == EVR_JDOC_OBJECT && evr_jdoc_first(&d, c) < 0 &&
          evr_jdoc_next(&d, c) < 0);
    CHECK(evr_jdoc_number(&d, evr_jdoc_get(&d, root, "k\"ey"), 0) == 7.0); /* an escaped key */
    /* missing values chain: -1 answers as a value of the wrong type */
    CHECK(evr_jdoc_get(&d, evr_jdoc_get(&d, root, "none"), "x") < 0);
    CHECK(evr_jdoc_count(&d, -1) == 0 && evr_jdoc_first(&d, -1) < 0 && evr_jdoc_type(&d, -1) < 0);
    CHECK(!evr_jdoc_string(&d, a, buf, sizeof buf) && buf[0] == 0);
    evr_jdoc_free(&d);
    free(text);

    /* \u escapes with a surrogate pair, a text that does not end in 0 */
    {
        static const char t[] = "[\"\\u00e9\\ud83d\\ude00\"]xyz";
        root = evr_jdoc_parse(&d, t, sizeof t - 4);
        CHECK(evr_jdoc_string(&d, evr_jdoc_first(&d, root), buf, sizeof buf) &&
              !strcmp(buf, "\xc3\xa9\xf0\x9f\x98\x80"));
        evr_jdoc_free(&d);
    }
    for (k = 0; k < (int)(sizeof bad / sizeof bad[0]); k++) {
        CHECK(evr_jdoc_parse(&d, bad[k], strlen(bad[k])) < 0 && !d.failed);
        evr_jdoc_free(&d);
    }
    /* nesting deeper than EVR_JDOC_MAX_DEPTH */
    {
        char deep[2 * (EVR_JDOC_MAX_DEPTH + 2)];
        for (k = 0; k < EVR_JDOC_MAX_DEPTH + 2; k++) {
            deep[k] = '[';
            deep[2 * (EVR_JDOC_MAX_DEPTH + 2) - 1 - k] = ']';
        }
        CHECK(evr_jdoc_parse(&d, deep, sizeof deep) < 0);
        evr_jdoc_free(&d);
        CHECK(evr_jdoc_parse(&d, deep + 2, sizeof deep - 4) >= 0);
        evr_jdoc_free(&d);
    }
}

/* Chunk compression: the shuffled layout, zero padding, and the pool's output equal to one
 * thread's. */
static void test_chunk_compress(void)
{
    enum { CE = 4096, NCH = 7 };
    evr_event *ev = calloc((size_t)CE * NCH, sizeof *ev);
    unsigned char *raw = malloc((size_t)CE * 8);
    evr_chunk_worker *scratch = evr_chunk_worker_new((size_t)CE * 8);
    size_t bound = evr_chunk_bound((size_t)CE * 8);
    unsigned char *dst = malloc(bound * 3 * NCH), *ref = malloc(bound * 3 * NCH);
    evr_chunk_job jobs[3 * NCH];
    uint64_t s = 4242;
    CHECK(ev && raw && scratch && dst && ref);
    if (!ev || !raw || !scratch || !dst || !ref) goto done;
    for (size_t i = 0; i < (size_t)CE * NCH; i++) {
        ev[i].t = (int64_t)(i * 37 + rng_next(&s) % 50) - 1000;
        ev[i].x = (uint16_t)rng_next(&s);
        ev[i].p = (int8_t)(rng_next(&s) & 1);
    }
    /* t, x and p of each chunk; the last chunk of each is partial */
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < NCH; k++) {
            evr_chunk_job *j = &jobs[c * NCH + k];
            size_t off = c == 0   ? offsetof(evr_event, t)
                         : c == 1 ? offsetof(evr_event, x)
                                  : offsetof(evr_event, p);
            memset(j, 0, sizeof *j);
            j->src = (const unsigned char *)(ev + (size_t)k * CE) + off;
            j->stride = sizeof(evr_event);
            j->elem_size = c == 0 ? 8 : c == 1 ? 2 : 1;
            j->count = k == NCH - 1 ? 1234 : CE;
            j->chunk_elems = CE;
            j->level = 1;
            j->dst = ref + (size_t)(c * NCH + k) * bound;
        }
    for (int i = 0; i < 3 * NCH; i++) {
        evr_chunk_job *j = &jobs[i];
        uLongf len = (uLongf)(CE * 8);
        size_t bad = 0, es = j->elem_size;
        CHECK(evr_chunk_compress(j, scratch));
        CHECK(j->ok && j->dst_size > 0 && j->dst_size <= bound);
        CHECK(uncompress(raw, &len, j->dst, (uLong)j->dst_size) == Z_OK);
        CHECK(len == CE * es);
        for (size_t e = 0; e < CE; e++)
            for (size_t b = 0; b < es; b++) {
                unsigned char want =
                    e < j->count ? ((const unsigned char *)j->src)[e * j->stride + b] : 0;
                if (raw[b * CE + e] != want) bad++;
            }
        CHECK(bad == 0);
        /* a full chunk of x: its low bytes are random, stored as the stream's first block (7
         * bits of entropy per byte or more); p (one plane, the last) is compressed */
        if (es == 2 && j->count == CE)
            CHECK(j->dst[2] == 0x00 && j->dst[3] == (CE & 0xff) && j->dst[4] == (CE >> 8));
        if (es == 1) CHECK(j->dst_size < (size_t)CE / 4);
    }
    /* the pool, with several threads and with the caller alone, makes the same bytes */
    for (int threads = 1; threads <= 3; threads += 2) {
        evr_chunk_pool *pool = evr_chunk_pool_new(threads, (size_t)CE * 8);
        CHECK(pool != NULL);
        if (!pool) continue;
        CHECK(evr_chunk_pool_threads(pool) >= 1 && evr_chunk_pool_threads(pool) <= threads);
        CHECK(evr_chunk_pool_run(pool, jobs, 0));
        for (int round = 0; round < 3; round++) {
            memset(dst, 0xa5, bound * 3 * NCH);
            for (int i = 0; i < 3 * NCH; i++) {
                jobs[i].dst = dst + (size_t)i * bound;
                jobs[i].ok = 0;
            }
            CHECK(evr_chunk_pool_run(pool, jobs, 3 * NCH));
            for (int i = 0; i < 3 * NCH; i++) {
                evr_chunk_job one = jobs[i];
                one.dst = ref + (size_t)i * bound;
                CHECK(evr_chunk_compress(&one, scratch));
                CHECK(jobs[i].ok && jobs[i].dst_size == one.dst_size);
                if (jobs[i].dst_size == one.dst_size)
                    CHECK(memcmp(jobs[i].dst, one.dst, one.dst_size) == 0);
            }
        }
        evr_chunk_pool_free(pool);
    }
    evr_chunk_pool_free(NULL);
    CHECK(evr_par_threads(16) >= 1 && evr_par_threads(16) <= 16);
    CHECK(evr_par_threads(1) == 1);
done:
    free(ev);
    free(raw);
    evr_chunk_worker_free(scratch);
    free(dst);
    free(ref);
}

/* ---- Prophesee EVT 2.0, EVT 3.0 and DAT ---- */

/* Sorted events over 22 s (more than one 2^24 us wrap of EVT 3.0) with runs of one timestamp,
 * dense rows of one polarity (vector words), a repeated pixel and the largest addresses. */
static evr_event *make_camera_events(size_t n)
{
    evr_event *ev = calloc(n, sizeof *ev);
    uint64_t s = 777;
    int64_t t = 3;
    for (size_t i = 0; ev && i < n; i++) {
        uint64_t r = rng_next(&s) % 100;
        if (i > 0 && r < 25 && ev[i - 1].x + 3 < W) { /* the same row, a few columns on */
            ev[i] = ev[i - 1];
            ev[i].x = (uint16_t)(ev[i - 1].x + 1 + rng_next(&s) % 3);
            continue;
        }
        if (i > 0 && r < 30) { /* the same timestamp elsewhere */
            ev[i].t = t;
        } else {
            t += (int64_t)(rng_next(&s) % 9000);
            ev[i].t = t;
        }
        ev[i].x = (uint16_t)(rng_next(&s) % W);
        ev[i].y = (uint16_t)(rng_next(&s) % H);
        ev[i].p = (int8_t)(rng_next(&s) & 1);
        if (i % 997 == 5) { /* the same pixel twice at one time */
            ev[i] = ev[i - 1];
        }
    }
    if (n > 10) {
        ev[n / 2].x = W - 1;
        ev[n / 2].y = H - 1;
    }
    return ev;
}

static void write_file(const char *path, const char *text, size_t len)
{
    FILE *fp = fopen(path, "wb");
    if (fp) {
        fwrite(text, 1, len, fp);
        fclose(fp);
    }
}

/* A read that must fail with EVR_ERR_FORMAT and a message naming the file and saying why. */
static void check_bad(const char *path, const char *why)
{
    evr_event *got = NULL;
    size_t ngot = 0;
    evr_error err;
    err.msg[0] = 0;
    CHECK(evr_events_read(path, &got, &ngot, NULL, NULL, &err) == EVR_ERR_FORMAT);
    CHECK(got == NULL);
    CHECK(strstr(err.msg, path) != NULL);
    CHECK(strstr(err.msg, why) != NULL);
    if (!strstr(err.msg, why)) fprintf(stderr, "expected '%s' in: %s\n", why, err.msg);
}

static void test_camera_format(const char *dir, const char *file, open_fn open, const evr_event *ev,
                               size_t n)
{
    char path[512], tmp[600], partial[600];
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_error err;
    size_t at = 0;
    evr_event *got = NULL;
    size_t ngot = 0;
    int width = 0, height = 0;
    snprintf(path, sizeof path, "%s/%s", dir, file);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    snprintf(partial, sizeof partial, "%s/partial_%s", dir, file);
    CHECK_OK(open(path, &meta, &w, &err));
    if (!w) return;
    for (int seg = 0; at < n; seg++) {
        size_t len = (size_t)(seg * 397 + 11) % 1500;
        if (len > n - at) len = n - at;
        CHECK_OK(w->write(w, ev + at, len, &err));
        CHECK_OK(w->flush(w, &err));
        at += len;
        if (seg == 3) { /* an interrupted run keeps every flushed event */
            CHECK(copy_file(tmp, partial));
            CHECK_OK(evr_events_read(partial, &got, &ngot, NULL, NULL, &err));
            CHECK(ngot == at);
            if (ngot == at) CHECK(same_events(got, ev, at));
            free(got);
            got = NULL;
            remove(partial);
        }
    }
    CHECK(!file_exists(path));
    CHECK_OK(w->finish(w, ev[n - 1].t + 1, &err));
    CHECK(file_exists(path) && !file_exists(tmp));
    CHECK_OK(evr_events_read(path, &got, &ngot, &width, &height, &err));
    CHECK(ngot == n);
    if (ngot == n) CHECK(same_events(got, ev, n));
    CHECK(width == W && height == H);
    free(got);

    /* a truncated file: one clear line, no events */
    {
        FILE *fp = fopen(path, "rb");
        char *data = malloc(1 << 22);
        size_t len = fp && data ? fread(data, 1, 1 << 22, fp) : 0;
        if (fp) fclose(fp);
        CHECK(len > 100);
        if (len > 100) {
            write_file(partial, data, len - 1);
            check_bad(partial, "truncated");
        }
        free(data);
        remove(partial);
    }
}

/* what a format cannot hold is refused, with the value in the message */
static void check_refused(const char *dir, const char *file, open_fn open, evr_event e,
                          const char *what)
{
    char path[512];
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_error err;
    snprintf(path, sizeof path, "%s/%s", dir, file);
    CHECK_OK(open(path, &meta, &w, &err));
    if (!w) return;
    err.msg[0] = 0;
    CHECK(w->write(w, &e, 1, &err) == EVR_ERR_ARG);
    CHECK(strstr(err.msg, what) != NULL);
    if (!strstr(err.msg, what)) fprintf(stderr, "expected '%s' in: %s\n", what, err.msg);
    w->abort(w);
    CHECK(!file_exists(path));
}

/* Writes ev[0 .. n) in batches of about `batch` events (the first about `first`) and returns the file's
 * bytes after its header lines (*len of them; NULL when it could not be written or read). */
static unsigned char *write_in_batches(const char *path, open_fn open, const evr_event *ev,
                                       size_t n, size_t first, size_t batch, size_t *len)
{
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_error err;
    unsigned char *data = NULL;
    size_t size = 0, at;
    FILE *fp;
    const char *end;
    *len = 0;
    CHECK_OK(open(path, &meta, &w, &err));
    if (!w) return NULL;
    for (at = 0; at < n;) {
        size_t k = at == 0 ? first : batch;
        if (k > n - at) k = n - at;
        /* EVT 3.0 vectors do not span writes: end each at a new timestamp, where none can */
        while (at + k < n && ev[at + k].t == ev[at + k - 1].t) k++;
        CHECK_OK(w->write(w, ev + at, k, &err));
        if (at == 0) CHECK_OK(w->flush(w, &err)); /* buffered bytes ahead of a large write */
        at += k;
    }
    CHECK_OK(w->finish(w, ev[n - 1].t + 1, &err));
    fp = fopen(path, "rb");
    if (fp && fseek(fp, 0, SEEK_END) == 0 && (size = (size_t)ftell(fp)) > 0 &&
        fseek(fp, 0, SEEK_SET) == 0 && (data = malloc(size + 1)) != NULL &&
        fread(data, 1, size, fp) != size) {
        free(data);
        data = NULL;
    }
    if (fp) fclose(fp);
    CHECK(data != NULL);
    if (!data) return NULL;
    data[size] = 0;
    if (data[0] != '%') { /* a bag: no header with a date */
        *len = size;
        return data;
    }
    end = strstr((const char *)data, "% end\n"); /* the header holds the date: skip it */
    CHECK(end != NULL);
    if (!end) {
        free(data);
        return NULL;
    }
    at = (size_t)(end - (const char *)data) + 6;
    *len = size - at;
    memmove(data, data + at, *len);
    return data;
}

/* The file at path reads back as ev[0 .. n); then it is removed. */
static void reads_back_and_goes(const char *path, const evr_event *ev, size_t n)
{
    evr_event *got = NULL;
    size_t ngot = 0;
    CHECK_OK(evr_events_read(path, &got, &ngot, NULL, NULL, &e_));
    CHECK(ngot == n);
    if (ngot == n) CHECK(same_events(got, ev, n));
    free(got);
    remove(path);
}

/* ev[0 .. n) written to path three ways: serially (batches too small for parts), in parts of
 * 140,000 events, and so through the pools of a 16-core machine (their pipelined ways); the
 * three files must hold the same bytes and read back as ev. Returns the serial file's bytes. */
static size_t same_bytes_in_parts(const char *path, open_fn open, const evr_event *ev, size_t n)
{
    size_t len_serial = 0, len_parts = 0, len_many = 0;
    unsigned char *serial =
        write_in_batches(path, open, ev, n, 1000, EVR_PAR_PACK_MIN / 2, &len_serial);
    unsigned char *parts = write_in_batches(path, open, ev, n, 1000, 140000, &len_parts);
    setenv("EVR_PAR_THREADS", "16", 1);
    unsigned char *many = write_in_batches(path, open, ev, n, 1000, 140000, &len_many);
    unsetenv("EVR_PAR_THREADS");
    CHECK(serial && parts && many && len_parts == len_serial && len_many == len_serial);
    if (len_parts != len_serial || len_many != len_serial)
        fprintf(stderr, "%s: %zu bytes in parts, %zu on 16 threads, %zu serially\n", path,
                len_parts, len_many, len_serial);
    if (serial && parts && len_parts == len_serial) CHECK(memcmp(serial, parts, len_serial) == 0);
    if (serial && many && len_many == len_serial) CHECK(memcmp(serial, many, len_serial) == 0);
    free(serial);
    free(parts);
    free(many);
    reads_back_and_goes(path, ev, n);
    return len_serial;
}

/* Large writes are packed in parallel parts (io/par_pack.h; the ROS bag its own way; text and
 * NPY too): the bytes must be those of the serial path (batches too small for parts), the file
 * must read back, and a bad event deep in a large write is refused as the serial path refuses
 * it. */
static void test_camera_parts(const char *root)
{
    static const struct {
        const char *file;
        open_fn open;
        evr_event bad; /* put in the middle of a large write */
        const char *why;
    } f[] = {
        {"parts_evt2.raw", evr_evt2_writer_open, {7, 2048, 5, 1, 0}, "(2048, 5)"},
        {"parts_evt3.raw", evr_evt3_writer_open, {7, 5, 2048, 1, 0}, "(5, 2048)"},
        {"parts.dat", evr_dat_writer_open, {INT64_C(1) << 32, 5, 6, 0, 0}, "4294967296 us"},
        {"parts.bag",
         evr_rosbag_writer_open,
         {(INT64_C(1) << 32) * 1000000, 5, 6, 0, 0},
         "4294967296000000 us"},
        {"parts.txt", evr_txt_writer_open, {1, 5, 6, 0, 0}, "out of time order (1 us after"},
        {"parts.npy", evr_npy_writer_open, {1, 5, 6, 0, 0}, "out of time order (1 us after"},
    };
    const size_t n = 300000;
    evr_event *ev = calloc(n, sizeof *ev);
    uint64_t s = 4242;
    int64_t t = 0;
    char path[600];
    CHECK(ev != NULL);
    if (!ev) return;
    /* runs of one time-high (64 us) word and jumps across several, parts starting in either;
     * rows of events at one time (EVT 3.0 vector words), some longer than one word holds */
    for (size_t i = 0; i < n; i++) {
        uint64_t r = rng_next(&s) % 100;
        if (i > 0 && r < 40 && ev[i - 1].x + 3 < W) {
            ev[i] = ev[i - 1];
            ev[i].x = (uint16_t)(ev[i - 1].x + 1 + rng_next(&s) % 3);
            continue;
        }
        t += r < 90 ? (int64_t)(r % 3) : (int64_t)(rng_next(&s) % 300);
        ev[i].t = t;
        ev[i].x = (uint16_t)(rng_next(&s) % W);
        ev[i].y = (uint16_t)(rng_next(&s) % H);
        ev[i].p = (int8_t)(rng_next(&s) & 1);
    }
    for (size_t k = 0; k < sizeof f / sizeof f[0]; k++) {
        evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
        evr_event_writer *w = NULL;
        evr_error err;
        evr_event *bad;
        snprintf(path, sizeof path, "%s/%s", root, f[k].file);
        CHECK(same_bytes_in_parts(path, f[k].open, ev, n) > n);

        /* the first bad event is refused, the later ones (out of order, past the range) not seen */
        bad = malloc(n * sizeof *bad);
        CHECK(bad != NULL);
        if (!bad) continue;
        memcpy(bad, ev, n * sizeof *bad);
        bad[200000] = f[k].bad;
        bad[200000].t = f[k].bad.t == 7 ? bad[199999].t : f[k].bad.t;
        bad[250000].t = 0;
        CHECK_OK(f[k].open(path, &meta, &w, &err));
        if (w) {
            err.msg[0] = 0;
            CHECK(w->write(w, bad, n, &err) == EVR_ERR_ARG);
            CHECK(strstr(err.msg, f[k].why) != NULL);
            if (!strstr(err.msg, f[k].why))
                fprintf(stderr, "expected '%s' in: %s\n", f[k].why, err.msg);
            w->abort(w);
        }
        CHECK(!file_exists(path));
        free(bad);
    }
    free(ev);
}

/* A bag whose messages are larger than its writes (a dense burst: 600,000 events in 0.12 s, about
 * 166,000 a 1/30 s message): writes that finish no chunk, and writes that finish one while the
 * next message keeps growing in the writer's buffer, must give the serial path's bytes; and its
 * finished chunks written behind (io/write_behind.h) must report a failed write. */
static void test_bag_dense_parts(const char *root)
{
    const size_t n = 600000;
    evr_event *ev = calloc(n, sizeof *ev);
    uint64_t s = 77;
    int64_t t = 0;
    char path[600];
    CHECK(ev != NULL);
    if (!ev) return;
    for (size_t i = 0; i < n; i++) {
        t += rng_next(&s) % 5 == 0;
        ev[i].t = t;
        ev[i].x = (uint16_t)(rng_next(&s) % W);
        ev[i].y = (uint16_t)(rng_next(&s) % H);
        ev[i].p = (int8_t)(rng_next(&s) & 1);
    }
    snprintf(path, sizeof path, "%s/dense.bag", root);
    CHECK(same_bytes_in_parts(path, evr_rosbag_writer_open, ev, n) > n * 13);

    /* a write behind that fails (a file size limit of 4 MB: EFBIG, as a full disk's ENOSPC):
     * a later write says why (no flush writes anything itself here), and the bag is not kept */
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_error err;
    evr_status st = EVR_OK;
    struct rlimit old, lim;
    void (*old_xfsz)(int) = signal(SIGXFSZ, SIG_IGN);
    char tmp[700];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    setenv("EVR_PAR_THREADS", "16", 1);
    CHECK_OK(evr_rosbag_writer_open(path, &meta, &w, &e_));
    CHECK(getrlimit(RLIMIT_FSIZE, &old) == 0);
    lim = old;
    lim.rlim_cur = 4 << 20;
    CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);
    err.msg[0] = 0;
    for (size_t at = 0; w && at < n && st == EVR_OK; at += 140000)
        st = w->write(w, ev + at, n - at < 140000 ? n - at : 140000, &err);
    CHECK(st == EVR_ERR_IO && strstr(err.msg, "File too large") != NULL);
    if (st != EVR_ERR_IO) fprintf(stderr, "a failed write behind: %d %s\n", (int)st, err.msg);
    if (w) CHECK(w->finish(w, ev[n - 1].t + 1, &err) != EVR_OK);
    CHECK(setrlimit(RLIMIT_FSIZE, &old) == 0);
    signal(SIGXFSZ, old_xfsz);
    unsetenv("EVR_PAR_THREADS");
    CHECK(!file_exists(path) && !file_exists(tmp));
    free(ev);
}

/* io/par_pack.c's two ways, whatever this machine's cores: packing then writing (a pool of two
 * threads) and writing each part as it is packed (four). A packer of 8 bytes an event; the
 * bytes land between what the stream held before and after, and an event out of order in a late
 * part leaves the file as it was (the pipelined way has written the parts before it: cut back). */
static size_t pp_bound(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    (void)ctx;
    (void)ev;
    return (b - a) * 8;
}

static void pp_put(unsigned char *o, const evr_event *e)
{
    const uint32_t t = (uint32_t)e->t;
    for (int i = 0; i < 4; i++) o[i] = (unsigned char)(t >> (8 * i));
    o[4] = (unsigned char)e->x;
    o[5] = (unsigned char)(e->x >> 8);
    o[6] = (unsigned char)e->y;
    o[7] = (unsigned char)(e->y >> 8);
}

static size_t pp_pack(const void *ctx, const evr_event *ev, size_t a, size_t b, unsigned char *out,
                      size_t room)
{
    (void)ctx;
    (void)room;
    for (size_t i = a; i < b; i++, out += 8) {
        if (i > 0 && ev[i].t < ev[i - 1].t) return SIZE_MAX;
        pp_put(out, &ev[i]);
    }
    return (b - a) * 8;
}

static void test_par_pack_ways(const char *root)
{
    const size_t n = 200000;
    const evr_par_packer packer = {pp_bound, pp_pack, NULL, NULL};
    evr_event *ev = calloc(n, sizeof *ev);
    unsigned char *want = malloc(n * 8 + 8);
    char path[600];
    uint64_t s = 99;
    CHECK(ev && want);
    if (!ev || !want) {
        free(ev);
        free(want);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        ev[i].t = (int64_t)(i / 3);
        ev[i].x = (uint16_t)(rng_next(&s) % W);
        ev[i].y = (uint16_t)(rng_next(&s) % H);
    }
    memcpy(want, "head", 4);
    for (size_t i = 0; i < n; i++) pp_put(want + 4 + 8 * i, &ev[i]);
    memcpy(want + 4 + 8 * n, "tail", 4);
    snprintf(path, sizeof path, "%s/par_pack.bin", root);
    for (int threads = 2; threads <= 4; threads += 2) {
        for (int bad = 0; bad <= 1; bad++) {
            evr_par_packing pk;
            size_t bytes = 0, len = 0;
            FILE *f = fopen(path, "w+b");
            CHECK(f != NULL);
            if (!f) continue;
            memset(&pk, 0, sizeof pk);
            pk.pool = evr_par_pool_new(threads); /* else the machine's cores decide */
            CHECK(evr_par_pool_threads(pk.pool) == threads);
            if (bad) ev[n * 7 / 8].t = 0;
            fputs("head", f); /* buffered: the large write flushes it first */
            const evr_par_pack_result r = evr_par_pack_write(&pk, &packer, ev, n, f, &bytes);
            if (bad) ev[n * 7 / 8].t = (int64_t)(n * 7 / 8 / 3);
            CHECK(r == (bad ? EVR_PAR_PACK_SERIAL : EVR_PAR_PACK_DONE));
            CHECK(bytes == (bad ? 0 : n * 8));
            if (!bad) fputs("tail", f);
            CHECK(fclose(f) == 0);
            char *got = NULL;
            CHECK_OK(evr_file_slurp(path, &got, &len, &e_));
            if (bad) CHECK(got && len == 4 && memcmp(got, "head", 4) == 0);
            else CHECK(got && len == n * 8 + 8 && memcmp(got, want, len) == 0);
            if (check_failures)
                fprintf(stderr, "par_pack: %d threads, bad %d: %zu bytes\n", threads, bad, len);
            free(got);
            evr_par_packing_free(&pk);
        }
    }
    remove(path);
    free(ev);
    free(want);
}

/* A large write with claim_room claims the room its parts may take (their bound) while they are
 * packed, and publishing the file frees what was claimed past its end: a packer bounded at 16
 * bytes an event that packs 8. Where the file system claims no room ahead, only the release is
 * checked. */
static size_t pp_bound_loose(const void *ctx, const evr_event *ev, size_t a, size_t b)
{
    (void)ctx;
    (void)ev;
    return (b - a) * 16;
}

static void test_par_pack_claims(const char *root)
{
    const size_t n = 200000;
    const evr_par_packer packer = {pp_bound_loose, pp_pack, NULL, NULL};
    evr_event *ev = calloc(n, sizeof *ev);
    char path[600], tmp[620];
    struct stat sb;
    CHECK(ev != NULL);
    if (!ev) return;
    for (size_t i = 0; i < n; i++) ev[i].t = (int64_t)(i / 3);
    snprintf(path, sizeof path, "%s/claims.bin", root);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    /* does this file system claim room ahead? */
    FILE *f = fopen(tmp, "wb");
    CHECK(f != NULL);
    if (!f) {
        free(ev);
        return;
    }
    const int claims = evr_file_claim(fileno(f), 0, (uint64_t)1 << 20) == 0 &&
                       fstat(fileno(f), &sb) == 0 && (uint64_t)sb.st_blocks * 512 >= (1u << 20);
    CHECK(ftruncate(fileno(f), 0) == 0);
    for (int threads = 2; threads <= 4; threads += 2) {
        evr_par_packing pk;
        size_t bytes = 0;
        memset(&pk, 0, sizeof pk);
        pk.pool = evr_par_pool_new(threads);
        pk.claim_room = 1;
        CHECK(evr_par_pack_write(&pk, &packer, ev, n, f, &bytes) == EVR_PAR_PACK_DONE);
        CHECK(bytes == n * 8);
        CHECK(fflush(f) == 0 && fstat(fileno(f), &sb) == 0);
        /* claimed: from where the write began (after the first's n * 8 bytes), its bound */
        if (claims)
            CHECK((uint64_t)sb.st_blocks * 512 >= (uint64_t)(threads / 2 - 1) * n * 8 + n * 16);
        evr_par_packing_free(&pk);
    }
    CHECK(fclose(f) == 0);
    CHECK(evr_file_publish(tmp, path) == 0);
    CHECK(stat(path, &sb) == 0 && sb.st_size == (off_t)(2 * n * 8));
    CHECK((uint64_t)sb.st_blocks * 512 <= 2 * n * 8 + 65536);
    if (check_failures)
        fprintf(stderr, "claims: %d; %lld bytes in %lld blocks\n", claims, (long long)sb.st_size,
                (long long)sb.st_blocks);
    remove(path);
    free(ev);
}

static void test_camera_formats(const char *root)
{
    const size_t n = 6000;
    evr_event *ev = make_camera_events(n);
    char dir[512], path[600];
    evr_event e = {0};
    CHECK(ev != NULL);
    if (!ev) return;
    CHECK(ev[n - 1].t > (INT64_C(1) << 24)); /* spans an EVT 3.0 wrap */
    snprintf(dir, sizeof dir, "%s/camera", root);
    CHECK(mkdir(dir, 0700) == 0);
    test_camera_format(dir, "events_evt2.raw", evr_evt2_writer_open, ev, n);
    test_camera_format(dir, "events_evt3.raw", evr_evt3_writer_open, ev, n);
    test_camera_format(dir, "events_td.dat", evr_dat_writer_open, ev, n);
    free(ev);

    memset(&e, 0, sizeof e);
    e.x = 2048;
    check_refused(dir, "a_evt2.raw", evr_evt2_writer_open, e, "(2048, 0)");
    check_refused(dir, "a_evt3.raw", evr_evt3_writer_open, e, "(2048, 0)");
    e.x = 0;
    e.y = 16384;
    check_refused(dir, "a.dat", evr_dat_writer_open, e, "(0, 16384)");
    e.y = 0;
    e.t = INT64_C(1) << 32;
    check_refused(dir, "a.dat", evr_dat_writer_open, e, "4294967296 us");
    e.t = INT64_C(1) << 34;
    check_refused(dir, "a_evt2.raw", evr_evt2_writer_open, e, "17179869184 us");

    /* bad input: one clear line, no crash */
    snprintf(path, sizeof path, "%s/bad.raw", dir);
    write_file(path, "hello", 5);
    check_bad(path, "not a Prophesee RAW file");
    write_file(path, "", 0);
    check_bad(path, "not a Prophesee RAW file");
    write_file(path, "% date x\n% end\n\x01\x02", 17);
    check_bad(path, "no '% evt' or '% format' line");
    write_file(path, "% evt 2.1\n% end\n", 16);
    check_bad(path, "unsupported RAW encoding 'evt 2.1'");
    write_file(path, "% evt 2.0\n% end\n\x00\x00\x00\x80\x00\x00\x00\x30", 24);
    check_bad(path, "unknown word type 0x3");
    write_file(path, "% evt 2.0\n% end\n\x00\x00\x00\x10", 20);
    check_bad(path, "before the first time-high word");
    write_file(path, "% evt 3.0\n% end\n\x00\x80\x01\x20", 20);
    check_bad(path, "before the first y word");
    write_file(path, "% evt 3.0\n% end\n\x00\x80\x05\x00\x00\x90", 22);
    check_bad(path, "unknown word type 0x9");
    remove(path);
    snprintf(path, sizeof path, "%s/bad.dat", dir);
    write_file(path, "% Version 2\n% end\n\x10\x08", 20);
    check_bad(path, "unsupported DAT events (type 0x10");
    write_file(path, "% Version 2\n% end\n", 18);
    check_bad(path, "truncated");
    write_file(path, "\x0c\x08", 2);
    check_bad(path, "not a Prophesee DAT file");
    remove(path);
}

/* ---- ROS1 bags ---- */

/* Round trip through the bag writer and reader, flushing after every segment; a copy of the
 * temporary file after a flush is a complete bag holding every finished message (the 30 Hz
 * windows before the last event's). Then what the reader refuses. */
static uint32_t get_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

/* The bag data[0 .. len) with each chunk's data compressed as rosbag does it, by bz2 (lz4 0) or
 * as an LZ4 frame (lz4 1), to *out_len bytes; compression_name replaces the header's "bz2" or
 * "lz4" (a name no reader knows). The chunk infos' offsets go stale: evray's reader reads the
 * records in turn. NULL when out of memory or a compressor failed. */
static unsigned char *compress_bag(const unsigned char *data, size_t len, int lz4,
                                   const char *compression_name, size_t *out_len)
{
    const size_t cap = 2 * len + 65536, magic = 13;
    unsigned char *out = malloc(cap);
    size_t at = magic, o = magic;
    if (!out) return NULL;
    memcpy(out, data, magic);
    while (at + 8 <= len) {
        const uint32_t hl = get_le32(data + at), dl = get_le32(data + at + 4 + hl);
        const unsigned char *h = data + at + 4, *d = data + at + 8 + hl;
        if (hl >= 8 && !memcmp(h + 4, "op=\x05", 4)) {
            const size_t name = strlen(compression_name), head = 8 + 4 + 12 + name + 4 + 9;
            unsigned char *c = out + o + 4 + head + 4;
            size_t room = cap - (o + 4 + head + 4), clen;
            if (lz4) {
                clen = LZ4F_compressFrame(c, room, d, dl, NULL);
                if (LZ4F_isError(clen)) break;
            } else {
                unsigned int n = (unsigned int)room;
                if (BZ2_bzBuffToBuffCompress((char *)c, &n, (char *)(uintptr_t)d, dl, 9, 0, 0) !=
                    BZ_OK)
                    break;
                clen = n;
            }
            unsigned char *p = out + o;
            put_le32(p, (uint32_t)head);
            put_le32(p + 4, 4);
            memcpy(p + 8, "op=\x05", 4);
            put_le32(p + 12, (uint32_t)(12 + name));
            memcpy(p + 16, "compression=", 12);
            memcpy(p + 28, compression_name, name);
            put_le32(p + 28 + name, 9);
            memcpy(p + 32 + name, "size=", 5);
            put_le32(p + 37 + name, dl);
            put_le32(p + 41 + name, (uint32_t)clen);
            o += 4 + head + 4 + clen;
        } else {
            memcpy(out + o, data + at, 8 + (size_t)hl + dl);
            o += 8 + (size_t)hl + dl;
        }
        at += 8 + (size_t)hl + dl;
    }
    if (at != len) {
        free(out);
        return NULL;
    }
    *out_len = o;
    return out;
}

static void test_rosbag(const char *root)
{
    const size_t n = 6000;
    evr_event *ev = make_camera_events(n), *got = NULL, e;
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    char dir[512], path[600], tmp[700], partial[700];
    size_t at = 0, ngot = 0;
    int width = 0, height = 0;
    CHECK(ev != NULL);
    if (!ev) return;
    snprintf(dir, sizeof dir, "%s/rosbag", root);
    CHECK(mkdir(dir, 0700) == 0);
    snprintf(path, sizeof path, "%s/events.bag", dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    snprintf(partial, sizeof partial, "%s/partial.bag", dir);
    CHECK_OK(evr_rosbag_writer_open(path, &meta, &w, &e_));
    for (int seg = 0; w && at < n; seg++) {
        size_t len = (size_t)(seg * 397 + 11) % 1500;
        if (len > n - at) len = n - at;
        CHECK_OK(w->write(w, ev + at, len, &e_));
        CHECK_OK(w->flush(w, &e_));
        at += len;
        if (seg == 3) {
            size_t done = 0;
            while (done < at && ev[done].t * 30 / 1000000 < ev[at - 1].t * 30 / 1000000) done++;
            CHECK(copy_file(tmp, partial));
            CHECK_OK(evr_events_read(partial, &got, &ngot, NULL, NULL, &e_));
            CHECK(ngot == done && done > 0);
            if (ngot == done) CHECK(same_events(got, ev, done));
            free(got);
            got = NULL;
            remove(partial);
        }
    }
    CHECK(!file_exists(path));
    if (w) CHECK_OK(w->finish(w, ev[n - 1].t + 1, &e_));
    CHECK(file_exists(path) && !file_exists(tmp));
    CHECK_OK(evr_events_read(path, &got, &ngot, &width, &height, &e_));
    CHECK(ngot == n);
    if (ngot == n) CHECK(same_events(got, ev, n));
    CHECK(width == W && height == H);
    free(got);
    got = NULL;

    /* a truncated file, and one that is no bag: one clear line, no events; its chunks compressed
     * by bz2 and lz4: the same events, and a chunk whose compressed data is cut or unknown: one
     * line */
    {
        FILE *fp = fopen(path, "rb");
        char *data = malloc(1 << 22);
        size_t len = fp && data ? fread(data, 1, 1 << 22, fp) : 0;
        if (fp) fclose(fp);
        CHECK(len > 5000);
        for (int lz4 = 0; lz4 < 2 && len > 5000; lz4++) {
            const char *name = lz4 ? "lz4" : "bz2";
            size_t clen = 0;
            unsigned char *c = compress_bag((const unsigned char *)data, len, lz4, name, &clen);
            CHECK(c != NULL && clen < len);
            if (!c) continue;
            write_file(partial, (const char *)c, clen);
            CHECK_OK(evr_events_read(partial, &got, &ngot, NULL, NULL, &e_));
            CHECK(ngot == n);
            if (ngot == n) CHECK(same_events(got, ev, n));
            free(got);
            got = NULL;
            free(c);
            c = compress_bag((const unsigned char *)data, len, lz4, "zip", &clen);
            if (c) {
                write_file(partial, (const char *)c, clen);
                check_bad(partial, "compression is none of none, bz2, lz4");
                free(c);
            }
            /* the first chunk's compressed data cut short by one byte, its record kept whole */
            c = compress_bag((const unsigned char *)data, len, lz4, name, &clen);
            if (c) {
                const size_t chunk = 4109; /* the first record after the bag header */
                const uint32_t hl = get_le32(c + chunk), dl = get_le32(c + chunk + 4 + hl);
                unsigned char *cut = malloc(clen);
                CHECK(cut != NULL);
                if (cut) {
                    const size_t end = chunk + 8 + hl + dl - 1;
                    memcpy(cut, c, end);
                    put_le32(cut + chunk + 4 + hl, dl - 1);
                    memcpy(cut + end, c + end + 1, clen - end - 1);
                    write_file(partial, (const char *)cut, clen - 1);
                    check_bad(partial,
                              lz4 ? "corrupt lz4 ROS bag chunk" : "corrupt bz2 ROS bag chunk");
                    free(cut);
                }
                free(c);
            }
        }
        if (len > 5000) {
            write_file(partial, data, len - 1);
            check_bad(partial, "truncated");
            write_file(partial, data, 5000);
            check_bad(partial, "truncated");
            data[1] = 'X';
            write_file(partial, data, len);
            check_bad(partial, "not a ROS bag 2.0 file");
        }
        free(data);
        write_file(partial, "#ROSBAG V2.0\n", 13);
        check_bad(partial, "no dvs_msgs/EventArray connection");
        remove(partial);
    }
    free(ev);

    /* ROS time holds whole seconds below 2^32 */
    memset(&e, 0, sizeof e);
    e.t = (INT64_C(1) << 32) * 1000000;
    check_refused(dir, "a.bag", evr_rosbag_writer_open, e, "4294967296000000 us");
    remove(path);
    rmdir(dir);
}

static void test_writers(const char *root, int *python_ok)
{
    const size_t n = 5000;
    int64_t last_t;
    evr_event *ev = make_events(n, &last_t);
    char *config = make_config();
    int64_t duration = last_t + 2500; /* not a whole number of milliseconds */
    char dir[512], path[600];
    CHECK(config != NULL);

    /* all events, an exact boundary count */
    snprintf(dir, sizeof dir, "%s/full", root);
    CHECK(mkdir(dir, 0700) == 0);
    for (size_t f = 0; f < NFORMATS; f++) test_format(dir, f, ev, n, duration, config);
    snprintf(path, sizeof path, "%s/events.h5", dir);
    check_ms_to_idx(path, ev, n, duration);
    CHECK(dir_entries(dir) == 3);

    /* a duration that ends on a millisecond, equal to the last event's time */
    {
        int64_t d2 = (last_t / 1000) * 1000;
        size_t n2 = 0;
        while (n2 < n && ev[n2].t <= d2) n2++;
        snprintf(dir, sizeof dir, "%s/boundary", root);
        CHECK(mkdir(dir, 0700) == 0);
        test_format(dir, 0, ev, n2, d2, config);
        snprintf(path, sizeof path, "%s/events.h5", dir);
        check_ms_to_idx(path, ev, n2, d2);
    }

    /* no events at all */
    snprintf(dir, sizeof dir, "%s/empty", root);
    CHECK(mkdir(dir, 0700) == 0);
    for (size_t f = 0; f < NFORMATS; f++) test_format(dir, f, ev, 0, 0, NULL);
    snprintf(path, sizeof path, "%s/events.h5", dir);
    check_ms_to_idx(path, ev, 0, 0);

    /* abort leaves nothing behind */
    snprintf(dir, sizeof dir, "%s/aborted", root);
    CHECK(mkdir(dir, 0700) == 0);
    for (size_t f = 0; f < NFORMATS; f++) {
        evr_writer_meta meta = {.width = W, .height = H, .config_json = config, .max_t_us = 0};
        evr_event_writer *w = NULL;
        snprintf(path, sizeof path, "%s/events.%s", dir, formats[f].ext);
        CHECK_OK(formats[f].open(path, &meta, &w, &e_));
        if (!w) continue;
        CHECK_OK(w->write(w, ev, n / 2, &e_));
        CHECK_OK(w->flush(w, &e_));
        CHECK_OK(w->write(w, ev + n / 2, 10, &e_));
        w->abort(w);
    }
    CHECK(dir_entries(dir) == 0);

    /* a folder that does not exist: a clear error, no crash */
    for (size_t f = 0; f < NFORMATS; f++) {
        evr_writer_meta meta = {.width = W, .height = H, .config_json = config, .max_t_us = 0};
        evr_event_writer *w = NULL;
        evr_error err;
        err.msg[0] = 0;
        snprintf(path, sizeof path, "%s/no/such/dir/events.%s", root, formats[f].ext);
        CHECK(formats[f].open(path, &meta, &w, &err) == EVR_ERR_IO);
        CHECK(w == NULL);
        CHECK(err.msg[0] != 0);
    }

    /* the reader refuses what it does not know */
    {
        evr_event *got = NULL;
        size_t ngot = 0;
        evr_error err;
        FILE *fp;
        CHECK(evr_events_read("x.csv", &got, &ngot, NULL, NULL, &err) == EVR_ERR_ARG);
        snprintf(path, sizeof path, "%s/bad.txt", root);
        fp = fopen(path, "w");
        if (fp) {
            fputs("# comment\n0.000001 1 2 1\n0.5 3\n", fp);
            fclose(fp);
        }
        CHECK(evr_events_read(path, &got, &ngot, NULL, NULL, &err) == EVR_ERR_FORMAT);
        CHECK(strstr(err.msg, ":3:") != NULL);
        fp = fopen(path, "w");
        if (fp) {
            fputs("# other tools' files\n\n1.5 3 4 -1\n2.0000005 5 6 1\n", fp);
            fclose(fp);
        }
        CHECK(evr_events_read(path, &got, &ngot, NULL, NULL, &err) == EVR_OK);
        CHECK(ngot == 2);
        if (ngot == 2) {
            CHECK(got[0].t == 1500000 && got[0].x == 3 && got[0].y == 4 && got[0].p == 0);
            CHECK(got[1].t == 2000001 && got[1].p == 1);
        }
        free(got);
        got = NULL;
        snprintf(path, sizeof path, "%s/bad.npy", root);
        fp = fopen(path, "w");
        if (fp) {
            fputs("not numpy", fp);
            fclose(fp);
        }
        CHECK(evr_events_read(path, &got, &ngot, NULL, NULL, &err) == EVR_ERR_FORMAT);
        snprintf(path, sizeof path, "%s/bad.h5", root);
        CHECK(evr_events_read(path, &got, &ngot, NULL, NULL, &err) == EVR_ERR_IO);
        CHECK(strstr(err.msg, "bad.h5") != NULL);
        remove(path);
        snprintf(path, sizeof path, "%s/bad.npy", root);
        remove(path);
        snprintf(path, sizeof path, "%s/bad.txt", root);
        remove(path);
    }

    test_h5_large(root);
    test_h5_t_range(root);
    test_h5_refused_in_bulk(root);
    test_npy_large(root);

    /* an independent reader */
    if (system("/usr/bin/python3 -c 'import h5py, numpy' >/dev/null 2>&1") == 0) {
        static const char script[] =
            "import json, sys, warnings\n"
            "warnings.simplefilter('ignore', UserWarning)\n"
            "import h5py, numpy as np, zlib\n"
            "def same_chunks(path, n, t_type):\n"
            "    # the layout DSEC tools expect, and chunks that hold, decompressed, the very bytes HDF5's\n"
            "    # shuffle filter makes (our deflate is libdeflate's, HDF5's zlib's: the streams differ)\n"
            "    ref_path = path + '.ref.h5'\n"
            "    with h5py.File(path, 'r') as f, h5py.File(ref_path, 'w') as r:\n"
            "        for name, dt in (('x', np.uint16), ('y', np.uint16), ('t', t_type), ('p', np.int8)):\n"
            "            d = f['events'][name]\n"
            "            assert d.dtype == dt and d.shape == (n,) and d.maxshape == (None,), (name, d.dtype, d.shape)\n"
            "            assert d.chunks == (65536,), d.chunks\n"
            "            assert d.compression == 'gzip' and d.compression_opts == 1 and d.shuffle, name\n"
            "            assert not d.fletcher32 and d.scaleoffset is None, name\n"
            "            dcpl = d.id.get_create_plist()\n"
            "            assert dcpl.get_nfilters() == 2\n"
            "            assert [dcpl.get_filter(i)[0] for i in range(2)] == [h5py.h5z.FILTER_SHUFFLE, h5py.h5z.FILTER_DEFLATE]\n"
            "            data = d[:]\n"
            "            g = r.create_dataset(name, data=data, chunks=(65536,), maxshape=(None,), shuffle=True,\n"
            "                                 compression='gzip', compression_opts=1)\n"
            "            for off in range(0, n, 65536):\n"
            "                mask, raw = d.id.read_direct_chunk((off,))\n"
            "                rmask, rraw = g.id.read_direct_chunk((off,))\n"
            "                assert mask == 0 and rmask == 0, (name, off, mask, rmask)\n"
            "                assert zlib.decompress(raw) == zlib.decompress(rraw), ('chunk differs from HDF5 filters', name, off)\n"
            "    import os\n"
            "    os.remove(ref_path)\n"
            "    with h5py.File(path, 'r') as f:\n"
            "        assert f['ms_to_idx'].chunks == (4096,) and f['ms_to_idx'].compression == 'gzip'\n"
            "        assert f['ms_to_idx'].shuffle and f['ms_to_idx'].maxshape == (None,)\n"
            "def check_large(d, n):\n"
            "    with h5py.File(d + '/events.h5', 'r') as f:\n"
            "        t = f['events']['t'][:]\n"
            "        assert len(t) == n and np.all(np.diff(t) >= 0)\n"
            "        ms = f['ms_to_idx'][:]\n"
            "        assert np.array_equal(ms, np.searchsorted(t, np.arange(len(ms)) * 1000, 'left'))\n"
            "        assert int(f.attrs['complete']) == 1\n"
            "    same_chunks(d + '/events.h5', n, np.int64)\n"
            "def check(d, n):\n"
            "    with h5py.File(d + '/events.h5', 'r') as f:\n"
            "        e = f['events']\n"
            "        x, y, t, p = e['x'][:], e['y'][:], e['t'][:], e['p'][:]\n"
            "        assert x.dtype == np.uint16 and y.dtype == np.uint16, (x.dtype, y.dtype)\n"
            "        assert t.dtype == np.uint32 and p.dtype == np.int8, (t.dtype, p.dtype)\n"
            "        assert len(x) == len(y) == len(t) == len(p) == n, (len(t), n)\n"
            "        assert np.all(np.diff(t) >= 0)\n"
            "        assert set(np.unique(p)) <= {0, 1}\n"
            "        ms = f['ms_to_idx'][:]\n"
            "        assert ms.dtype == np.uint64\n"
            "        assert np.array_equal(ms, np.searchsorted(t, np.arange(len(ms)) * 1000, 'left'))\n"
            "        assert f['t_offset'][()] == 0 and f['t_offset'].dtype == np.int64\n"
            "        assert int(f.attrs['width']) == 640 and int(f.attrs['height']) == 480\n"
            "        assert int(f.attrs['complete']) == 1\n"
            "        cfg = f.attrs['config']\n"
            "        cfg = cfg.decode() if isinstance(cfg, bytes) else cfg\n"
            "        json.loads(cfg)\n"
            "    same_chunks(d + '/events.h5', n, np.uint32)\n"
            "    a = np.load(d + '/events.npy')\n"
            "    assert a.dtype == np.dtype([('t', '<i8'), ('x', '<u2'), ('y', '<u2'), ('p', 'i1')]), a.dtype\n"
            "    assert a.dtype.itemsize == 13 and a.shape == (n,), a.shape\n"
            "    assert np.array_equal(a['t'], t) and np.array_equal(a['x'], x)\n"
            "    assert np.array_equal(a['y'], y) and np.array_equal(a['p'], p)\n"
            "    m = np.loadtxt(d + '/events.txt', ndmin=2).reshape(-1, 4)\n"
            "    assert m.shape == (n, 4), m.shape\n"
            "    assert np.array_equal(np.round(m[:, 0] * 1e6).astype(np.int64), t)\n"
            "    assert np.array_equal(m[:, 1], x) and np.array_equal(m[:, 2], y) and np.array_equal(m[:, 3], p)\n"
            "    assert np.all(np.diff(m[:, 0]) >= 0)\n"
            "check(sys.argv[1] + '/full', int(sys.argv[2]))\n"
            "check(sys.argv[1] + '/empty', 0)\n"
            "check_large(sys.argv[1] + '/large', int(sys.argv[3]))\n"
            "print('python readers agree')\n";
        char cmd[1400];
        FILE *fp;
        snprintf(path, sizeof path, "%s/check.py", root);
        fp = fopen(path, "w");
        CHECK(fp != NULL);
        if (fp) {
            fputs(script, fp);
            fclose(fp);
            snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s %zu %zu", path, root, n, large_n);
            fflush(stdout);
            CHECK(system(cmd) == 0);
            *python_ok = 1;
        }
    } else {
        printf(
            "test_writers: python3 with h5py and numpy not found; skipping the independent reader\n");
    }
    free(config);
    free(ev);
}

/* ---- JSON ---- */

static void check_json(char *got, const char *expect)
{
    CHECK(got != NULL);
    if (got && strcmp(got, expect) != 0) {
        fprintf(stderr, "json: got      %s\njson: expected %s\n", got, expect);
        CHECK(0);
    }
    free(got);
}

static void test_json(void)
{
    evr_json j;

    evr_json_init(&j, 0);
    evr_json_begin_object(&j);
    evr_json_key(&j, "s");
    evr_json_string(&j, "q\"b\\n\nt\tc\x01\x1f"
                        "e\xc3\xa9");
    evr_json_key(&j, "a");
    evr_json_begin_array(&j);
    evr_json_integer(&j, 1);
    evr_json_begin_object(&j);
    evr_json_end_object(&j);
    evr_json_begin_array(&j);
    evr_json_end_array(&j);
    evr_json_begin_object(&j);
    evr_json_key(&j, "k");
    evr_json_begin_array(&j);
    evr_json_boolean(&j, 1);
    evr_json_boolean(&j, 0);
    evr_json_null(&j);
    evr_json_end_array(&j);
    evr_json_end_object(&j);
    evr_json_end_array(&j);
    evr_json_key(&j, "n");
    evr_json_begin_array(&j);
    evr_json_number(&j, 0.1);
    evr_json_number(&j, 1.0 / 3.0);
    evr_json_number(&j, 1e300);
    evr_json_number(&j, 0.0 / 0.0);
    evr_json_number(&j, -1.0 / 0.0);
    evr_json_number(&j, -2.5);
    evr_json_float(&j, 0.2f);
    evr_json_float(&j, 1e-7f);
    evr_json_integer(&j, INT64_MIN);
    evr_json_unsigned(&j, UINT64_MAX);
    evr_json_end_array(&j);
    evr_json_key(&j, "z");
    evr_json_string(&j, NULL);
    evr_json_end_object(&j);
    check_json(
        evr_json_take(&j),
        "{\"s\":\"q\\\"b\\\\n\\nt\\tc\\u0001\\u001fe\xc3\xa9\",\"a\":[1,{},[],{\"k\":[true,false,null]}],"
        "\"n\":[0.1,0.3333333333333333,1e+300,null,null,-2.5,0.2,1e-07,-9223372036854775808,"
        "18446744073709551615],\"z\":null}");

    evr_json_init(&j, 1);
    evr_json_begin_object(&j);
    evr_json_key(&j, "a");
    evr_json_integer(&j, 1);
    evr_json_key(&j, "b");
    evr_json_begin_array(&j);
    evr_json_integer(&j, 2);
    evr_json_begin_object(&j);
    evr_json_key(&j, "c");
    evr_json_string(&j, "d");
    evr_json_end_object(&j);
    evr_json_end_array(&j);
    evr_json_key(&j, "e");
    evr_json_begin_object(&j);
    evr_json_end_object(&j);
    evr_json_end_object(&j);
    check_json(evr_json_take(&j),
               "{\n  \"a\": 1,\n  \"b\": [\n    2,\n    {\n      \"c\": \"d\"\n    }\n  ],\n"
               "  \"e\": {}\n}");

    /* a builder can be reused after take */
    evr_json_begin_array(&j);
    evr_json_end_array(&j);
    check_json(evr_json_take(&j), "[]");
    evr_json_string(&j, "top");
    check_json(evr_json_take(&j), "\"top\"");

    /* misuse: value without key, key in an array, mismatched end, unclosed, two top-level values */
    evr_json_init(&j, 0);
    evr_json_begin_object(&j);
    evr_json_integer(&j, 1);
    evr_json_end_object(&j);
    CHECK(evr_json_take(&j) == NULL);
    evr_json_begin_array(&j);
    evr_json_key(&j, "k");
    evr_json_end_array(&j);
    CHECK(evr_json_take(&j) == NULL);
    evr_json_begin_array(&j);
    evr_json_end_object(&j);
    CHECK(evr_json_take(&j) == NULL);
    evr_json_begin_object(&j);
    evr_json_key(&j, "k");
    CHECK(evr_json_take(&j) == NULL);
    evr_json_begin_object(&j);
    evr_json_key(&j, "k");
    evr_json_end_object(&j);
    CHECK(evr_json_take(&j) == NULL);
    evr_json_integer(&j, 1);
    evr_json_integer(&j, 2);
    CHECK(evr_json_take(&j) == NULL);
    for (int i = 0; i < EVR_JSON_MAX_DEPTH + 1; i++) evr_json_begin_array(&j);
    for (int i = 0; i < EVR_JSON_MAX_DEPTH + 1; i++) evr_json_end_array(&j);
    CHECK(evr_json_take(&j) == NULL);
    for (int i = 0; i < EVR_JSON_MAX_DEPTH; i++) evr_json_begin_array(&j);
    for (int i = 0; i < EVR_JSON_MAX_DEPTH; i++) evr_json_end_array(&j);
    {
        char *t = evr_json_take(&j);
        CHECK(t != NULL && strlen(t) == 2 * EVR_JSON_MAX_DEPTH);
        free(t);
    }
    /* a long string grows the buffer */
    {
        char *big = malloc(100001), *t;
        memset(big, 'a', 100000);
        big[100000] = 0;
        big[500] = '"';
        evr_json_string(&j, big);
        t = evr_json_take(&j);
        CHECK(t != NULL && strlen(t) == 100003);
        free(t);
        free(big);
    }
}

/* ---- previews ---- */

static void test_event_frames(const char *root)
{
    evr_event_frame f;
    evr_event ev[16];
    char path[600];
    int iw = 0, ih = 0, ic = 0, n = 0;
    unsigned char *img;
    memset(ev, 0, sizeof ev);
    /* (1,2): ON; (3,4): OFF; (5,6): two OFF one ON -> OFF; (7,0): one each, ON last -> ON */
#define EV(T, X, Y, P) \
    do {               \
        ev[n].t = (T); \
        ev[n].x = (X); \
        ev[n].y = (Y); \
        ev[n].p = (P); \
        n++;           \
    } while (0)
    EV(0, 1, 2, 1);
    EV(1, 3, 4, 0);
    EV(2, 5, 6, 0);
    EV(3, 5, 6, 1);
    EV(4, 5, 6, 0);
    EV(5, 7, 0, 0);
    EV(6, 7, 0, 1);
    EV(7, 100, 100, 1); /* the last one is outside the image */
#undef EV
    CHECK_OK(evr_event_frame_init(&f, 10, 8, &e_));
    evr_event_frame_add(&f, ev, (size_t)n);
    CHECK(f.events == 7);
    snprintf(path, sizeof path, "%s/events.png", root);
    CHECK_OK(evr_event_frame_write_png(&f, path, &e_));
    img = stbi_load(path, &iw, &ih, &ic, 0);
    CHECK(img != NULL);
    if (img && iw == 10 && ih == 8 && ic == 3) {
#define PX(X, Y) (img + 3 * ((Y)*10 + (X)))
        CHECK(PX(1, 2)[0] == 0 && PX(1, 2)[1] == 0 && PX(1, 2)[2] == 255);
        CHECK(PX(3, 4)[0] == 255 && PX(3, 4)[1] == 0 && PX(3, 4)[2] == 0);
        CHECK(PX(5, 6)[0] == 255 && PX(5, 6)[2] == 0);
        CHECK(PX(7, 0)[0] == 0 && PX(7, 0)[2] == 255);
        CHECK(PX(0, 0)[0] == 255 && PX(0, 0)[1] == 255 && PX(0, 0)[2] == 255);
        CHECK(PX(9, 7)[0] == 255 && PX(9, 7)[1] == 255 && PX(9, 7)[2] == 255);
#undef PX
    } else CHECK(0);
    if (img) stbi_image_free(img);
    evr_event_frame_clear(&f);
    CHECK(f.events == 0 && f.on[2 * 10 + 1] == 0);
    evr_event_frame_release(&f);

    /* a series of windows */
    {
        evr_event_preview *p = NULL;
        evr_event e2[5];
        char dir[560];
        memset(e2, 0, sizeof e2);
        e2[0].t = 10;
        e2[1].t = 999;
        e2[2].t = 1000;
        e2[3].t = 3500;
        e2[4].t = 3999;
        snprintf(dir, sizeof dir, "%s/series", root);
        CHECK(mkdir(dir, 0700) == 0);
        CHECK_OK(evr_event_preview_new(4, 4, 1000, dir, "ev", &p, &e_));
        if (p) {
            CHECK_OK(evr_event_preview_add(p, e2, 3, &e_));
            CHECK(evr_event_preview_frames(p) == 1);
            CHECK_OK(evr_event_preview_advance(p, 2000, &e_));
            CHECK(evr_event_preview_frames(p) == 2);
            CHECK_OK(evr_event_preview_add(p, e2 + 3, 2, &e_));
            CHECK(evr_event_preview_frames(p) == 3);
            CHECK_OK(evr_event_preview_finish(p, 4500, &e_));
            CHECK(evr_event_preview_frames(p) == 5);
            evr_event_preview_release(p);
        }
        CHECK(dir_entries(dir) == 5);
        snprintf(path, sizeof path, "%s/ev_000004.png", dir);
        CHECK(file_exists(path));
    }
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Write speed of the HDF5 writer: 10 M events per simulated second in segments of 1/30 s, each
 * written and flushed (the worst case: the simulation flushes about once a second, write_queue.h;
 * kept so that the figures compare with earlier ones). 10 M events in optimized builds, 1 M
 * otherwise; EVR_H5_BENCH_EVENTS sets another count (0 skips). */
/* Writing speed of one writer on 10 M events (1 M in debug builds; EVR_H5_BENCH_EVENTS sets it). */
static void bench_writer(const char *root, const char *name, open_fn open, const char *file)
{
#ifdef NDEBUG
    size_t n = 10000000;
#else
    size_t n = 1000000;
#endif
    const size_t seg = 333333;
    const char *env = getenv("EVR_H5_BENCH_EVENTS");
    evr_writer_meta meta = {.width = W, .height = H, .config_json = "{}", .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_event *ev;
    int64_t last_t;
    char path[600];
    double t0, t1;
    if (env) n = (size_t)strtoull(env, NULL, 10);
    if (n == 0) return;
    /* 10 events per microsecond, as the GPU backend makes them, over the whole image */
    ev = malloc(n * sizeof *ev);
    CHECK(ev != NULL);
    if (!ev) return;
    {
        uint64_t s = 777;
        for (size_t i = 0; i < n; i++) {
            ev[i].t = (int64_t)(i / 10);
            ev[i].x = (uint16_t)(rng_next(&s) % W);
            ev[i].y = (uint16_t)(rng_next(&s) % H);
            ev[i].p = (int8_t)(rng_next(&s) & 1);
        }
        last_t = ev[n - 1].t;
    }
    snprintf(path, sizeof path, "%s/%s", root, file);
    t0 = now_s();
    CHECK_OK(open(path, &meta, &w, &e_));
    for (size_t at = 0; w && at < n; at += seg) {
        CHECK_OK(w->write(w, ev + at, n - at < seg ? n - at : seg, &e_));
        CHECK_OK(w->flush(w, &e_));
    }
    if (w) CHECK_OK(w->finish(w, last_t + 1, &e_));
    t1 = now_s();
    {
        struct stat st;
        long long size = stat(path, &st) == 0 ? (long long)st.st_size : -1;
        printf(
            "test_writers: %s writer: %zu events in %.3f s: %.2f M events/s (%.2f bytes/event)\n",
            name, n, t1 - t0, (double)n / (t1 - t0) * 1e-6, (double)size / (double)n);
    }
    remove(path);
    free(ev);
}

int main(void)
{
    char root[] = "/tmp/evr_test_writers_XXXXXX";
    int python_ok = 0;
    if (!mkdtemp(root)) {
        perror("mkdtemp");
        return 1;
    }
    test_json();
    test_json_read();
    test_chunk_compress();
    test_chunk_stored_blocks();
    test_deflate_runs();
    test_writers(root, &python_ok);
    test_camera_formats(root);
    test_camera_parts(root);
    test_bag_dense_parts(root);
    test_par_pack_ways(root);
    test_par_pack_claims(root);
    test_rosbag(root);
    test_event_frames(root);
    bench_writer(root, "hdf5", evr_h5_writer_open, "bench.h5");
    bench_writer(root, "evt2", evr_evt2_writer_open, "bench_evt2.raw");
    bench_writer(root, "evt3", evr_evt3_writer_open, "bench_evt3.raw");
    bench_writer(root, "dat", evr_dat_writer_open, "bench.dat");
    bench_writer(root, "rosbag", evr_rosbag_writer_open, "bench.bag");
    bench_writer(root, "aedat4", evr_aedat4_writer_open, "bench.aedat4");
    if (check_failures == 0) remove_tree(root);
    else fprintf(stderr, "test_writers: files kept in %s\n", root);
    (void)python_ok;
    return check_report("test_writers");
}
