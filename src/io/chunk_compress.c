/* Shuffle + deflate of dataset chunks, in parallel (see chunk_compress.h). HDF5 1.10's H5Z
 * shuffle filter transposes the bytes of the whole chunk (and leaves 1-byte elements untouched);
 * its deflate filter reads any zlib stream, which libdeflate makes faster than zlib's compress2,
 * with smaller output (docs/benchmarks.md: the writer thread 2.3x faster, files 2% smaller);
 * byte planes of nearly random bytes go into the stream stored, not compressed (zlib_stream).
 * tests/test_writers.c reads the chunks back with zlib and through HDF5. */
#include "io/chunk_compress.h"
#include "io/deflate_runs.h"
#include "par_pool.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <libdeflate.h>

/* A leading byte plane of the shuffled chunk whose bytes have at least STORE_BITS bits of
 * entropy (order 0) and repeat the byte before them at most once in STORE_REPEATS is stored as it
 * is: deflate could save at most an eighth of it, and such planes were the slowest to compress
 * (the low bytes of x and y: 123 MB/s against 240-390 MB/s for the others, 42% of the writer's
 * compression time for 0.6% of the file, docs/benchmarks.md). Repeats catch what the histogram
 * misses: the low byte of sorted timestamps looks random to it, but 90% of its bytes repeat the
 * one before, and deflate shrinks it six-fold. */
#define STORE_BITS 7.0
#define STORE_REPEATS 8

/* The planes after those stored go into one block of runs (deflate_runs.h) instead of through
 * libdeflate when at least (RUNS_REPEATS - 1) / RUNS_REPEATS of their bytes repeat the one before:
 * the timestamps (97% on the eye) and the high byte of y. Files grew 4% on the eye, the writer's
 * compression time fell by nearly half (docs/benchmarks.md). */
#define RUNS_REPEATS 8

/* A thread's scratch (the shuffled chunk) and its compressor (made for one level at a time). */
struct evr_chunk_worker {
    unsigned char *scratch;
    struct libdeflate_compressor *comp;
    int level;
};

/* The threads of a par_pool, each compressing with a worker of its own. */
struct evr_chunk_pool {
    evr_par_pool *par;
    int threads;                /* the caller included */
    evr_chunk_worker **workers; /* one per thread; [0] is the caller's */
    evr_chunk_job *jobs;        /* the list being compressed */
    size_t njobs;
};

size_t evr_chunk_bound(size_t raw_bytes)
{
    /* any level; stored blocks of the leading planes: 5 bytes each per 65,535 */
    return libdeflate_zlib_compress_bound(NULL, raw_bytes) + 5 * (raw_bytes / 65535 + 2);
}

evr_chunk_worker *evr_chunk_worker_new(size_t max_chunk_bytes)
{
    evr_chunk_worker *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    if (!(w->scratch = malloc(max_chunk_bytes ? max_chunk_bytes : 1))) {
        free(w);
        return NULL;
    }
    w->level = -1;
    return w;
}

void evr_chunk_worker_free(evr_chunk_worker *w)
{
    if (!w) return;
    libdeflate_free_compressor(w->comp);
    free(w->scratch);
    free(w);
}

/* The shuffle for one element size: es is a constant where it is inlined, so the inner loop is
 * unrolled. One pass over the source writes es output streams. */
static inline void shuffle_es(unsigned char *out, const unsigned char *src, size_t stride,
                              size_t count, size_t chunk_elems, size_t es)
{
    for (size_t i = 0; i < count; i++) {
        const unsigned char *e = src + i * stride;
        for (size_t b = 0; b < es; b++) out[b * chunk_elems + i] = e[b];
    }
    if (count < chunk_elems)
        for (size_t b = 0; b < es; b++)
            memset(out + b * chunk_elems + count, 0, chunk_elems - count);
}

/* Whether p[0 .. n), of which `repeats` bytes equal the one before them (the runs deflate would
 * find; evr_deflate_repeats), is random enough to store: few repeats and many bits per byte
 * (order-0 entropy of its histogram). */
static int plane_random(const unsigned char *p, size_t n, size_t repeats)
{
    uint32_t h[4][256] = {{0}}; /* four histograms: no store waits on the one before */
    size_t i = 0;
    if (n < 2 || repeats * STORE_REPEATS > n) return 0;
    for (; i + 4 <= n; i += 4) {
        h[0][p[i]]++;
        h[1][p[i + 1]]++;
        h[2][p[i + 2]]++;
        h[3][p[i + 3]]++;
    }
    for (; i < n; i++) h[0][p[i]]++;
    double bits = 0.0;
    for (int v = 0; v < 256; v++) {
        const uint32_t c = h[0][v] + h[1][v] + h[2][v] + h[3][v];
        if (c) bits -= (double)c * log2((double)c / (double)n);
    }
    return bits >= STORE_BITS * (double)n;
}

/* The zlib stream (RFC 1950) of the shuffled chunk raw (es planes of n bytes): the leading planes
 * that look random (plane_random; all but the last at most) in stored deflate blocks, which end
 * on a byte, so that the rest follows them as the stream's last blocks, a block of runs when the
 * rest is mostly runs, else libdeflate's raw deflate stream; then the Adler-32 of all of raw.
 * Returns its length, 0 when out of room. */
static size_t zlib_stream(struct libdeflate_compressor *comp, const unsigned char *raw, size_t n,
                          size_t es, unsigned char *dst, size_t room)
{
    size_t stored = 0, at = 2, total = n * es, rest_repeats = 0;
    for (size_t j = 0; j < es; j++) { /* each plane's repeats, counted once */
        const size_t r = evr_deflate_repeats(raw + j * n, n);
        if (j == stored && j + 1 < es && plane_random(raw + j * n, n, r)) stored++;
        else
            rest_repeats +=
                r + (j > stored && raw[j * n] == raw[j * n - 1]); /* and across planes */
    }
    if (room < 6) return 0;
    dst[0] = 0x78; /* deflate, 32 KiB window */
    dst[1] = 0x01; /* no dictionary; (0x78 * 256 + 0x01) % 31 == 0 */
    for (size_t done = 0; done < stored * n;) {
        size_t len = stored * n - done;
        if (len > 65535) len = 65535;
        if (at + 5 + len > room) return 0;
        dst[at++] = 0x00; /* BFINAL 0, BTYPE 00 (stored), then padding to the byte */
        dst[at++] = (unsigned char)(len & 0xff);
        dst[at++] = (unsigned char)(len >> 8);
        dst[at++] = (unsigned char)(~len & 0xff);
        dst[at++] = (unsigned char)((~len >> 8) & 0xff);
        memcpy(dst + at, raw + done, len);
        at += len;
        done += len;
    }
    if (room < at + 4) return 0;
    const unsigned char *rest = raw + stored * n;
    const size_t rest_n = total - stored * n;
    size_t z = 0;
    if (rest_repeats * RUNS_REPEATS >= rest_n * (RUNS_REPEATS - 1))
        z = evr_deflate_runs(rest, rest_n, dst + at, room - at - 4);
    if (z == 0)
        z = libdeflate_deflate_compress(comp, rest, rest_n, dst + at,
                                        room - at - 4); /* else, or too long */
    if (z == 0) return 0;
    at += z;
    const uint32_t a = libdeflate_adler32(1, raw, total);
    dst[at++] = (unsigned char)(a >> 24);
    dst[at++] = (unsigned char)(a >> 16);
    dst[at++] = (unsigned char)(a >> 8);
    dst[at++] = (unsigned char)a;
    return at;
}

int evr_chunk_compress(evr_chunk_job *job, evr_chunk_worker *w)
{
    const unsigned char *src = (const unsigned char *)job->src;
    unsigned char *scratch = w->scratch;
    size_t raw = job->chunk_elems * job->elem_size, count = job->count;
    if (count > job->chunk_elems) count = job->chunk_elems;
    if (!w->comp || w->level != job->level) {
        libdeflate_free_compressor(w->comp);
        w->comp = libdeflate_alloc_compressor(job->level);
        w->level = w->comp ? job->level : -1;
        if (!w->comp) {
            job->ok = 0;
            job->dst_size = 0;
            return 0;
        }
    }
    switch (job->elem_size) {
    case 1: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 1); break;
    case 2: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 2); break;
    case 4: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 4); break;
    case 8: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, 8); break;
    default: shuffle_es(scratch, src, job->stride, count, job->chunk_elems, job->elem_size); break;
    }
    const size_t len = zlib_stream(w->comp, scratch, job->chunk_elems, job->elem_size, job->dst,
                                   evr_chunk_bound(raw));
    job->ok = len > 0;
    job->dst_size = len;
    return job->ok;
}

static void compress_part(void *ctx, int k, int thread)
{
    evr_chunk_pool *p = ctx;
    evr_chunk_compress(&p->jobs[k], p->workers[thread]);
}

evr_chunk_pool *evr_chunk_pool_new(int threads, size_t max_chunk_bytes)
{
    evr_chunk_pool *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    p->par = evr_par_pool_new(threads);
    p->threads =
        evr_par_pool_threads(p->par); /* threads that cannot be started leave a smaller pool */
    p->workers = calloc((size_t)p->threads, sizeof *p->workers);
    int ok = p->par && p->workers;
    for (int i = 0; ok && i < p->threads; i++)
        ok = (p->workers[i] = evr_chunk_worker_new(max_chunk_bytes)) != NULL;
    if (!ok) {
        evr_chunk_pool_free(p);
        return NULL;
    }
    return p;
}

void evr_chunk_pool_start(evr_chunk_pool *p, evr_chunk_job *jobs, size_t n)
{
    p->jobs = jobs;
    p->njobs = n;
    evr_par_pool_start(p->par, (int)n, compress_part, p);
}

int evr_chunk_pool_wait(evr_chunk_pool *p)
{
    int ok = 1;
    evr_par_pool_wait(p->par);
    for (size_t k = 0; k < p->njobs; k++) ok &= p->jobs[k].ok;
    p->jobs = NULL;
    p->njobs = 0;
    return ok;
}

int evr_chunk_pool_run(evr_chunk_pool *p, evr_chunk_job *jobs, size_t n)
{
    if (n == 0) return 1;
    evr_chunk_pool_start(p, jobs, n);
    return evr_chunk_pool_wait(p);
}

int evr_chunk_pool_threads(const evr_chunk_pool *p) { return p->threads; }

void evr_chunk_pool_free(evr_chunk_pool *p)
{
    if (!p) return;
    evr_par_pool_free(p->par); /* finishes the parts it has started */
    for (int i = 0; p->workers && i < p->threads; i++) evr_chunk_worker_free(p->workers[i]);
    free(p->workers);
    free(p);
}
