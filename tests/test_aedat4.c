/* The AEDAT 4.0 writer and reader (io/aedat4_writer.c, io/aedat4_read.c): events round trip in
 * uneven segments with a flush after each (a copy of the temporary file after a flush is a
 * complete file holding every event so far), the file's bytes depend only on the events (one
 * write, small writes, large writes packed in parallel parts), a dense millisecond spreads over
 * several packets (checked by tests/test_aedat4.py, which reads the files with dv-processing and
 * aedat), what the format cannot hold is refused, and bad or damaged files give one line. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "evray.h"
#include "io/event_reader.h"
#include "io/event_writer.h"
#include "io/par_pack.h"

#define W 346
#define H 260

static uint64_t rng_next(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 33;
}

/* Sorted events: runs of one timestamp, empty milliseconds, a millisecond of more events than a
 * packet holds (from event dense on), the largest addresses. */
static evr_event *make_events(size_t n, size_t dense)
{
    evr_event *ev = calloc(n, sizeof *ev);
    uint64_t s = 2024;
    int64_t t = 5;
    for (size_t i = 0; ev && i < n; i++) {
        uint64_t r = rng_next(&s) % 100;
        if (i == dense) t = (t / 1000 + 1) * 1000; /* 40000 events in 800 us from here */
        if (i >= dense && i < dense + 40000) t += (i - dense) % 50 == 49;
        else if (r < 30) t += 0;
        else if (r < 33) t = (t / 1000 + 5) * 1000;
        else t += (int64_t)(rng_next(&s) % 200);
        ev[i].t = t;
        ev[i].x = (uint16_t)(rng_next(&s) % W);
        ev[i].y = (uint16_t)(rng_next(&s) % H);
        ev[i].p = (int8_t)(rng_next(&s) & 1);
    }
    if (ev && n > 10) {
        ev[n / 3].x = W - 1;
        ev[n / 3].y = H - 1;
    }
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

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *d = NULL;
    long size;
    *len = 0;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (d = malloc((size_t)size + 1)) && fread(d, 1, (size_t)size, f) == (size_t)size)
        *len = (size_t)size;
    else {
        free(d);
        d = NULL;
    }
    fclose(f);
    return d;
}

static void write_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (f) {
        fwrite(data, 1, len, f);
        fclose(f);
    }
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Every event of path, which must be ev[0 .. n). */
static void check_reads(const char *path, const evr_event *ev, size_t n)
{
    evr_event *got = NULL;
    size_t ngot = 0;
    int width = 0, height = 0;
    CHECK_OK(evr_events_read(path, &got, &ngot, &width, &height, &e_));
    CHECK(ngot == n);
    if (ngot == n) CHECK(same_events(got, ev, n));
    CHECK(width == W && height == H);
    free(got);
}

/* Writes ev[0 .. n) in writes of `batch` events (the first `first`), flushing after each when
 * flush is set; returns the file's bytes (*len). With copy_at, a copy of the temporary file
 * after the flush that follows event copy_at goes to `partial`. */
static unsigned char *write_events(const char *path, const evr_event *ev, size_t n, size_t first,
                                   size_t batch, int flush, size_t copy_at, const char *partial,
                                   size_t *len)
{
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    char tmp[600];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    *len = 0;
    remove(path);
    CHECK_OK(evr_aedat4_writer_open(path, &meta, &w, &e_));
    if (!w) return NULL;
    CHECK(file_exists(tmp) && !file_exists(path));
    for (size_t at = 0; at < n;) {
        size_t k = at == 0 ? first : batch;
        if (k > n - at) k = n - at;
        CHECK_OK(w->write(w, ev + at, k, &e_));
        if (flush) CHECK_OK(w->flush(w, &e_));
        at += k;
        if (partial && at == copy_at) {
            size_t plen;
            unsigned char *p = slurp(tmp, &plen);
            CHECK(p != NULL);
            if (p) write_file(partial, p, plen);
            free(p);
        }
    }
    CHECK_OK(w->finish(w, n ? ev[n - 1].t + 1 : 0, &e_));
    CHECK(file_exists(path) && !file_exists(tmp));
    return slurp(path, len);
}

static void test_round_trip(const char *dir)
{
    const size_t n = 120000;
    evr_event *ev = make_events(n, 60000);
    char path[512], partial[512], other[512];
    size_t len = 0, len1 = 0, len2 = 0;
    unsigned char *a, *b, *c;
    CHECK(ev != NULL);
    if (!ev) return;
    snprintf(path, sizeof path, "%s/events.aedat4", dir);
    snprintf(partial, sizeof partial, "%s/partial.aedat4", dir);
    snprintf(other, sizeof other, "%s/other.aedat4", dir);

    /* uneven writes, flushed after each: a copy after a flush holds every event so far */
    a = write_events(path, ev, n, 7, 1333, 1, 7 + 1333 * 20, partial, &len);
    CHECK(a != NULL && len > 100);
    check_reads(path, ev, n);
    check_reads(partial, ev, 7 + 1333 * 20);

    /* one write; and large writes in parallel parts, never flushed: the same bytes */
    b = write_events(other, ev, n, n, n, 0, 0, NULL, &len1);
    CHECK(b && len1 == len && memcmp(a, b, len) == 0);
    c = write_events(other, ev, n, 5, 3 * EVR_PAR_PACK_MIN + 17, 0, 0, NULL, &len2);
    CHECK(c && len2 == len && memcmp(a, c, len) == 0);
    free(b);
    free(c);
    /* a large write that starts a new millisecond: it closes the open packet with none of its
     * events, in parallel with its own packets */
    size_t k = EVR_PAR_PACK_MIN + 1;
    while (k < n && ev[k].t / 1000 == ev[k - 1].t / 1000) k++;
    CHECK(k < n - EVR_PAR_PACK_MIN);
    c = write_events(other, ev, n, k, n - k, 0, 0, NULL, &len2);
    CHECK(c && len2 == len && memcmp(a, c, len) == 0);
    free(c);

    free(a);
    free(ev);
    remove(path);
    remove(partial);
    remove(other);
}

/* A run with no events, flushed or not: a valid file of none. */
static void test_empty(const char *dir)
{
    char path[512];
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_event *got = NULL;
    size_t ngot = 1;
    int width = 0, height = 0;
    snprintf(path, sizeof path, "%s/empty.aedat4", dir);
    for (int flush = 0; flush < 2; flush++) {
        CHECK_OK(evr_aedat4_writer_open(path, &meta, &w, &e_));
        if (!w) return;
        if (flush) CHECK_OK(w->flush(w, &e_));
        CHECK_OK(w->finish(w, 1000, &e_));
        CHECK_OK(evr_events_read(path, &got, &ngot, &width, &height, &e_));
        CHECK(got == NULL && ngot == 0 && width == W && height == H);
        remove(path);
    }
}

/* x and y are int16: 32768 is refused, with the pixel in the message; nothing is left. */
static void test_refused(const char *dir)
{
    char path[512];
    evr_writer_meta meta = {.width = W, .height = H, .config_json = NULL, .max_t_us = 0};
    evr_event_writer *w = NULL;
    evr_event e[2];
    evr_error err;
    memset(e, 0, sizeof e);
    e[0].t = 10;
    e[1].t = 20;
    e[1].y = 32768;
    snprintf(path, sizeof path, "%s/refused.aedat4", dir);
    CHECK_OK(evr_aedat4_writer_open(path, &meta, &w, &err));
    if (!w) return;
    err.msg[0] = 0;
    CHECK(w->write(w, e, 2, &err) == EVR_ERR_ARG);
    CHECK(strstr(err.msg, "(0, 32768)") != NULL);
    e[1].y = 0;
    e[1].t = 5; /* out of time order */
    CHECK(w->write(w, e + 1, 1, &err) == EVR_ERR_ARG);
    CHECK(strstr(err.msg, "out of time order") != NULL);
    w->abort(w);
    CHECK(!file_exists(path));
    snprintf(path, sizeof path, "%s/refused.aedat4.tmp", dir);
    CHECK(!file_exists(path));
}

/* A read that must fail with EVR_ERR_FORMAT and one line naming the file and saying why. */
static void check_bad(const char *path, const void *data, size_t len, const char *why)
{
    evr_event *got = NULL;
    size_t ngot = 0;
    evr_error err;
    write_file(path, data, len);
    err.msg[0] = 0;
    CHECK(evr_events_read(path, &got, &ngot, NULL, NULL, &err) == EVR_ERR_FORMAT);
    CHECK(got == NULL);
    CHECK(strstr(err.msg, path) != NULL && !strchr(err.msg, '\n'));
    CHECK(strstr(err.msg, why) != NULL);
    if (!strstr(err.msg, why)) fprintf(stderr, "expected '%s' in: %s\n", why, err.msg);
    free(got);
}

/* The first s in d[0 .. len); NULL: none. */
static unsigned char *find(unsigned char *d, size_t len, const char *s)
{
    const size_t n = strlen(s);
    for (size_t i = 0; i + n <= len; i++)
        if (!memcmp(d + i, s, n)) return d + i;
    return NULL;
}

/* Bad files: wrong magic and version, a truncated or corrupt header, FlatBuffer, frame, packet
 * or data table. The good file's layout: version line (14 bytes), IOHeader size at 14, its root
 * offset at 18, compression at 42, dataTablePosition at 46, then the packets. */
static void test_bad_files(const char *dir)
{
    const size_t n = 3000;
    evr_event *ev = make_events(n, n);
    char path[512], bad[512];
    size_t len = 0, head;
    unsigned char *d, *b;
    snprintf(path, sizeof path, "%s/good.aedat4", dir);
    snprintf(bad, sizeof bad, "%s/bad.aedat4", dir);
    d = ev ? write_events(path, ev, n, n, n, 0, 0, NULL, &len) : NULL;
    b = d ? malloc(len) : NULL;
    CHECK(d && b && len > 1000);
    if (!d || !b || len <= 1000) {
        free(ev);
        free(d);
        return;
    }
    head = 18 + ((size_t)d[14] | (size_t)d[15] << 8 | (size_t)d[16] << 16);
    check_bad(bad, "", 0, "not an AEDAT file");
    check_bad(bad, "#!AER-DAT3.1\r\n#Format: RAW\r\n", 28, "AEDAT version '3.1' is not read");
    check_bad(bad, d, 20, "truncated AEDAT 4.0 header");
    check_bad(bad, d, len - 1, "truncated LZ4 frame in the data table");
    check_bad(bad, d, head + (len - head) / 2, "truncated AEDAT 4.0 file");
    /* with no data table (an interrupted run's file between flushes), packets to the end */
    memcpy(b, d, len);
    memset(b + 46, 0xff, 8);
    check_bad(bad, b, head + 5, "truncated AEDAT 4.0 packet header");
    check_bad(bad, b, head + 100, "truncated AEDAT 4.0 packet at byte");
    memcpy(b, d, len);
    b[0] = 'X';
    check_bad(bad, b, len, "not an AEDAT file");
    memcpy(b, d, len);
    b[18] = 0xf0; /* the root table far past the header */
    check_bad(bad, b, len, "corrupt AEDAT 4.0 header (IOHeader FlatBuffer)");
    memcpy(b, d, len);
    b[42] = 9;
    check_bad(bad, b, len, "unknown AEDAT 4.0 compression 9");
    memcpy(b, d, len);
    {
        unsigned char *e = find(b, head, "EVTS</attr>");
        CHECK(e != NULL);
        if (e) memcpy(e, "FRME", 4);
        check_bad(bad, b, len, "no event stream (typeIdentifier EVTS)");
    }
    memcpy(b, d, len);
    {
        unsigned char *x = find(b, head, "</node>");
        CHECK(x != NULL);
        if (x) x[1] = 'x'; /* a node never closed */
        check_bad(bad, b, len, "no well-formed XML");
    }
    memcpy(b, d, len);
    for (size_t k = head + 20; k < head + 60; k++) b[k] ^= 0x5a;
    check_bad(bad, b, len, "corrupt LZ4 frame in the packet at byte");
    memcpy(b, d, len);
    b[head + 7] = 0x80; /* a negative packet size */
    check_bad(bad, b, len, "corrupt AEDAT 4.0 packet header at byte");
    remove(bad);
    remove(path);
    free(b);
    free(d);
    free(ev);
}

/* Random damage (bytes changed anywhere, most in the header and the first packet; the file cut
 * anywhere): every read either succeeds or fails with one line, never crashes (the sanitizer
 * build runs this too). */
static void test_damage(const char *dir)
{
    const size_t n = 2000;
    evr_event *ev = make_events(n, n);
    char path[512], bad[512];
    size_t len = 0;
    uint64_t s = 99;
    unsigned char *d, *b;
    snprintf(path, sizeof path, "%s/good.aedat4", dir);
    snprintf(bad, sizeof bad, "%s/damaged.aedat4", dir);
    d = ev ? write_events(path, ev, n, n, n, 0, 0, NULL, &len) : NULL;
    b = d ? malloc(len) : NULL;
    CHECK(d && b && len > 1000);
    for (int k = 0; b && k < 600; k++) {
        evr_event *got = NULL;
        size_t ngot = 0, cut = len;
        evr_error err;
        evr_status st;
        memcpy(b, d, len);
        if (k % 4 == 3) cut = (size_t)(rng_next(&s) % len);
        else
            for (int j = 0; j < 1 + k % 3; j++) {
                const size_t span = rng_next(&s) & 1 ? 1200 : len;
                b[rng_next(&s) % span] = (unsigned char)rng_next(&s);
            }
        write_file(bad, b, cut);
        err.msg[0] = 0;
        st = evr_events_read(bad, &got, &ngot, NULL, NULL, &err);
        CHECK(st == EVR_OK || (st == EVR_ERR_FORMAT && got == NULL && strstr(err.msg, bad) &&
                               !strchr(err.msg, '\n')));
        free(got);
    }
    remove(bad);
    remove(path);
    free(b);
    free(d);
    free(ev);
}

int main(void)
{
    char root[] = "/tmp/evr_test_aedat4_XXXXXX";
    if (!mkdtemp(root)) {
        perror("mkdtemp");
        return 1;
    }
    test_round_trip(root);
    test_empty(root);
    test_refused(root);
    test_bad_files(root);
    test_damage(root);
    rmdir(root);
    return check_report("test_aedat4");
}
