/* HDF5 event files in the layout of the DSEC data sets:
 *
 *   /events/x  uint16   /events/y  uint16   /events/t  uint32 (us)   /events/p  int8 (1 ON, 0 OFF)
 *   /ms_to_idx uint64   index of the first event with t >= i ms, i = 0 .. ceil(duration/1 ms)
 *   with event ids (evr_writer_meta.event_ids): /events/id uint16 (evr_event.id) and
 *   /instances naming each id (io/h5_instances.h)
 *   /t_offset  int64    0 (our timestamps start at the simulation start)
 *   attributes on /: width, height (int32), config (JSON text), complete (int8, 1 once finished)
 *
 * t is uint32 as in DSEC ("the storage of timestamp data with fewer bits", t_offset 0) when the
 * run's timestamps stay below 2^32 us (71.6 minutes: evr_writer_meta.max_t_us), else int64; an
 * event outside uint32's range is an error, never wrapped. Half the bytes of int64 to compress:
 * its constant high bytes still cost libdeflate time.
 * The event datasets and ms_to_idx are extendible and chunked (shuffle + deflate). HDF5 runs
 * its filters serially inside H5Dwrite, which cannot keep up with the GPU backend, so the event
 * chunks are filtered here instead, by a pool of threads (chunk_compress.c makes the very bytes
 * HDF5's shuffle and deflate filters would make), and stored with H5Dwrite_chunk: readers see
 * the same datasets, filters and chunks. Events are staged until a batch of chunks is full;
 * flush() stores the full chunks staged and flushes the file, so the temporary file of a killed
 * run is readable and holds every event up to the last flush but those of the last partial
 * chunk (fewer than 65,536), which stay in memory until finish() stores them (zero beyond the
 * data, as HDF5 fills it). ms_to_idx is small, goes through H5Dwrite and is written by finish().
 * Storing the partial chunk at each flush and replacing it later would leave holes whose places
 * depend on when the (timed) flushes came: as it is, the same events give the same bytes
 * however the flushes fell, and no object carries a time stamp (evr_h5_create_reproducible).
 * HDF5's automatic error printing is switched off around every call (H5E_BEGIN_TRY) and its
 * error stack is turned into the message instead. */
#include "io/event_formats.h"
#include "io/chunk_compress.h"
#include "io/file_commit.h"
#include "io/file_room.h"
#include "io/h5_file.h"
#include "io/h5_instances.h"
#include "par_pool.h"

#include <errno.h>
#include <hdf5.h>
#include <inttypes.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define H5W_CHUNK (1u << 16) /* elements per chunk */
#define H5W_MS_CHUNK 4096u
#define H5W_DEFLATE \
    1 /* libdeflate's level 1: smaller than zlib's level 3 and 2-3x faster (chunk_compress.c) */
#define H5W_MAX_THREADS 16 /* compression threads, the caller included */
#define H5W_MIN_BATCH 4    /* chunks staged before they are stored, at least */
#define H5W_COLUMNS 5      /* t, x, y, p, id (with event ids): the largest first but id */
/* Staging (checking and copying arriving events, finding the millisecond index) on this many
 * threads, the writer's included: alone it was most of the writer thread's time and bound by
 * one core's memory bandwidth (the eye's 218.7 M events: 0.8 of 1.15 s busy, H100 machine) */
#define H5W_STAGE_THREADS 4
#define H5W_STAGE_PARTS 16
#define H5W_STAGE_MIN (1u << 15) /* events: fewer are staged by the writer's thread alone */
/* file room claimed beyond the data for HDF5's own metadata (claim_room) */
#define H5W_METADATA_ROOM ((uint64_t)1 << 20)

/* A stage of events with the compression jobs of its chunks and their output room. */
typedef struct {
    evr_event *stage;
    evr_chunk_job *jobs;
    unsigned char *zbuf;
} h5_set;

typedef struct {
    evr_event_writer base; /* first: the interface pointer is the writer pointer */
    char *path, *tmp;
    hid_t file, group;
    hid_t ds_x, ds_y, ds_t, ds_p, ds_id, ds_ms;
    int ncols; /* columns written: H5W_COLUMNS with event ids, else one fewer */
    /* staged events, from dataset index written on (p already 0 or 1), in set[fill].stage */
    size_t nstage, cap_stage; /* cap_stage: a whole number of chunks */
    uint64_t written;         /* events in full chunks stored (a multiple of H5W_CHUNK) */
    uint64_t tail_stored;     /* events of the partial chunk at written stored by a flush */
    uint64_t extent;          /* length of the event datasets */
    uint64_t total;           /* events received (written + staged) */
    /* compression: one job per column and chunk, each with its output room in zbuf; two sets,
     * set[fill] staging, the other compressing (inflight) a full batch from dataset index
     * inflight_at */
    evr_chunk_pool *pool;
    evr_par_pool *stage_pool;
    h5_set set[2];
    int fill, inflight;
    uint64_t inflight_at;
    size_t batch; /* chunks in a full stage */
    /* a full batch whose storing failed (salvage stores it again): its set and first index */
    int unstored, unstored_set;
    uint64_t unstored_at;
    int64_t last_t;
    int have_last;
    int t32; /* events/t is uint32 (else int64) */
    /* ms_to_idx entries computed but not yet appended */
    uint64_t *ms;
    size_t nms, cap_ms;
    uint64_t ms_written; /* entries in the dataset */
    uint64_t next_ms;    /* index of the next entry to compute */
} h5_writer;

/* Collects the most specific HDF5 error description (the walk starts where the error arose). */
typedef struct {
    char desc[1024]; /* room for the errno after a long file name */
    int got;
} h5_walk_data;

static herr_t h5_walk(unsigned n, const H5E_error2_t *e, void *data)
{
    h5_walk_data *d = (h5_walk_data *)data;
    (void)n;
    if (!d->got && e->desc && e->desc[0]) { /* keep the most specific one */
        snprintf(d->desc, sizeof d->desc, "%s", e->desc);
        d->got = 1;
    }
    return 0;
}

static evr_status h5_fail(evr_error *err, const char *what, const char *path)
{
    h5_walk_data d;
    const char *at;
    int code;
    d.desc[0] = 0;
    d.got = 0;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, h5_walk, &d);
    H5Eclear2(H5E_DEFAULT);
    /* a failed system call: HDF5's description names the time, the descriptor, the buffer...
     * and errno, which is all the user needs ("No space left on device") */
    if (d.got && (at = strstr(d.desc, "errno = ")) != NULL && sscanf(at + 8, "%d", &code) == 1)
        snprintf(err->msg, sizeof err->msg, "hdf5: %s %s: %s", what, path, strerror(code));
    else if (d.got) snprintf(err->msg, sizeof err->msg, "hdf5: %s %s: %s", what, path, d.desc);
    else snprintf(err->msg, sizeof err->msg, "hdf5: %s %s", what, path);
    return EVR_ERR_IO;
}

static hid_t make_extendible(hid_t loc, const char *name, hid_t type, hsize_t chunk)
{
    hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED}, ch[1] = {chunk};
    hid_t space = H5Screate_simple(1, dims, maxdims);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t ds = -1;
    if (space >= 0 && dcpl >= 0 && H5Pset_obj_track_times(dcpl, 0) >= 0 &&
        H5Pset_chunk(dcpl, 1, ch) >= 0 && H5Pset_shuffle(dcpl) >= 0 &&
        H5Pset_deflate(dcpl, H5W_DEFLATE) >= 0)
        ds = H5Dcreate2(loc, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (dcpl >= 0) H5Pclose(dcpl);
    if (space >= 0) H5Sclose(space);
    return ds;
}

/* Appends n elements of memory type mtype to the 1-D dataset ds that holds old elements. */
static herr_t append(hid_t ds, hid_t mtype, const void *data, uint64_t old, size_t n)
{
    hsize_t size[1] = {(hsize_t)(old + n)}, start[1] = {(hsize_t)old}, count[1] = {(hsize_t)n};
    hid_t fspace = -1, mspace = -1;
    herr_t r = -1;
    if (n == 0) return 0;
    if (H5Dset_extent(ds, size) < 0) return -1;
    fspace = H5Dget_space(ds);
    mspace = H5Screate_simple(1, count, NULL);
    if (fspace >= 0 && mspace >= 0 &&
        H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL) >= 0)
        r = H5Dwrite(ds, mtype, mspace, fspace, H5P_DEFAULT, data);
    if (mspace >= 0) H5Sclose(mspace);
    if (fspace >= 0) H5Sclose(fspace);
    return r;
}

static herr_t write_scalar_attr(hid_t loc, const char *name, hid_t ftype, hid_t mtype,
                                const void *value)
{
    hid_t space = H5Screate(H5S_SCALAR), a = -1;
    herr_t r = -1;
    if (space >= 0) {
        if (H5Aexists(loc, name) > 0) a = H5Aopen(loc, name, H5P_DEFAULT);
        else a = H5Acreate2(loc, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
    }
    if (a >= 0) r = H5Awrite(a, mtype, value);
    if (a >= 0) H5Aclose(a);
    if (space >= 0) H5Sclose(space);
    return r;
}

static herr_t write_string_attr(hid_t loc, const char *name, const char *text)
{
    hid_t type = H5Tcopy(H5T_C_S1);
    herr_t r = -1;
    if (type >= 0 && H5Tset_size(type, H5T_VARIABLE) >= 0 && H5Tset_cset(type, H5T_CSET_UTF8) >= 0)
        r = write_scalar_attr(loc, name, type, type, &text);
    if (type >= 0) H5Tclose(type);
    return r;
}

static herr_t write_scalar_dataset(hid_t loc, const char *name, hid_t ftype, hid_t mtype,
                                   const void *value)
{
    hid_t space = H5Screate(H5S_SCALAR), dcpl = H5Pcreate(H5P_DATASET_CREATE), ds = -1;
    herr_t r = -1;
    if (space >= 0 && dcpl >= 0 && H5Pset_obj_track_times(dcpl, 0) >= 0)
        ds = H5Dcreate2(loc, name, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (dcpl >= 0) H5Pclose(dcpl);
    if (ds >= 0) r = H5Dwrite(ds, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, value);
    if (ds >= 0) H5Dclose(ds);
    if (space >= 0) H5Sclose(space);
    return r;
}

static void close_all(h5_writer *w)
{
    hid_t *ids[] = {&w->ds_x, &w->ds_y, &w->ds_t, &w->ds_p, &w->ds_id, &w->ds_ms};
    H5E_BEGIN_TRY
    {
        for (size_t i = 0; i < sizeof ids / sizeof ids[0]; i++)
            if (*ids[i] >= 0) {
                H5Dclose(*ids[i]);
                *ids[i] = -1;
            }
        if (w->group >= 0) {
            H5Gclose(w->group);
            w->group = -1;
        }
        if (w->file >= 0) {
            H5Fclose(w->file);
            w->file = -1;
        }
        H5Eclear2(H5E_DEFAULT);
    }
    H5E_END_TRY;
}

static void free_writer(h5_writer *w)
{
    evr_chunk_pool_free(w->pool);
    evr_par_pool_free(w->stage_pool);
    free(w->path);
    free(w->tmp);
    for (int i = 0; i < 2; i++) {
        free(w->set[i].stage);
        free(w->set[i].jobs);
        free(w->set[i].zbuf);
    }
    free(w->ms);
    free(w);
}

/* Room for `extra` more ms_to_idx entries; 0 when out of memory (nothing changed). */
static int reserve_ms(h5_writer *w, size_t extra)
{
    if (w->nms + extra <= w->cap_ms) return 1;
    size_t cap = w->cap_ms ? w->cap_ms : 1024;
    while (cap < w->nms + extra) cap *= 2;
    uint64_t *p = realloc(w->ms, cap * sizeof *p);
    if (!p) return 0;
    w->ms = p;
    w->cap_ms = cap;
    return 1;
}

static int push_ms(h5_writer *w, uint64_t value)
{
    if (!reserve_ms(w, 1)) return 0;
    w->ms[w->nms++] = value;
    w->next_ms++;
    return 1;
}

/* Element size, byte offset in evr_event and dataset of column c (largest elements first). A
 * uint32 t is the low four bytes of evr_event's int64 (little-endian, as the datasets). */
static size_t column_size(const h5_writer *w, int c)
{
    static const size_t size[H5W_COLUMNS] = {sizeof(int64_t), sizeof(uint16_t), sizeof(uint16_t),
                                             sizeof(int8_t), sizeof(uint16_t)};
    return c == 0 && w->t32 ? sizeof(uint32_t) : size[c];
}

static size_t column_offset(int c)
{
    static const size_t off[H5W_COLUMNS] = {offsetof(evr_event, t), offsetof(evr_event, x),
                                            offsetof(evr_event, y), offsetof(evr_event, p),
                                            offsetof(evr_event, id)};
    return off[c];
}

static hid_t column_dataset(const h5_writer *w, int c)
{
    return c == 0 ? w->ds_t : c == 1 ? w->ds_x : c == 2 ? w->ds_y : c == 3 ? w->ds_p : w->ds_id;
}

/* Bytes of zbuf that the compressed chunks of one column take in a full batch. */
static size_t column_room(const h5_writer *w, int c)
{
    return w->batch * evr_chunk_bound(H5W_CHUNK * column_size(w, c));
}

/* The jobs of set's chunks 0 .. nchunks, into its zbuf (chunk k holds count(k) events: the full
 * chunk size but for a last partial one of rest events when nchunks > nfull). */
static size_t make_jobs(const h5_writer *w, h5_set *set, size_t nchunks, size_t nfull, size_t rest)
{
    const evr_event *stage = set->stage;
    evr_chunk_job *jobs = set->jobs;
    unsigned char *room = set->zbuf;
    size_t njobs = 0;
    for (int c = 0; c < w->ncols; c++) {
        size_t bound = evr_chunk_bound(H5W_CHUNK * column_size(w, c));
        for (size_t k = 0; k < nchunks; k++) {
            evr_chunk_job *j = &jobs[njobs++];
            j->src = (const unsigned char *)(stage + k * H5W_CHUNK) + column_offset(c);
            j->stride = sizeof(evr_event);
            j->elem_size = column_size(w, c);
            j->count = k < nfull ? H5W_CHUNK : rest;
            j->chunk_elems = H5W_CHUNK;
            j->level = H5W_DEFLATE;
            j->dst = room + k * bound;
        }
        room += column_room(w, c);
    }
    return njobs;
}

/* Claims room for `bytes` more of the file, with H5W_METADATA_ROOM for what HDF5 adds to place
 * them (chunk index nodes, the metadata a flush writes), before HDF5 writes (io/file_room.h): HDF5
 * does not survive every failed write (after a chunk write that met a full disk, a later write
 * of that chunk succeeds yet leaves it out of its dataset's chunk index), so a full disk is met
 * here, with nothing written. */
static evr_status claim_room(h5_writer *w, uint64_t bytes, evr_error *err)
{
    void *handle = NULL;
    haddr_t eoa = 0;
    struct stat sb;
    herr_t r;
    H5E_BEGIN_TRY
    {
        r = H5Fget_vfd_handle(w->file, H5P_DEFAULT, &handle);
        if (r >= 0) r = H5Fget_eoa(w->file, &eoa);
    }
    H5E_END_TRY;
    if (r < 0 || !handle) return EVR_OK; /* not a plain file: nothing to claim ahead */
    const int fd = *(const int *)handle;
    if (fstat(fd, &sb) != 0) return EVR_OK;
    /* HDF5 writes below its end of allocation and allocates past it */
    const uint64_t size = (uint64_t)sb.st_size, from = size < eoa ? size : (uint64_t)eoa,
                   end = (size > eoa ? size : (uint64_t)eoa) + bytes + H5W_METADATA_ROOM;
    if (evr_file_claim(fd, from, end - from) != 0) {
        snprintf(err->msg, sizeof err->msg, "hdf5 writer: cannot write %s: %s", w->tmp,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

/* Stores the compressed chunks of jobs (nchunks per column) from dataset index at on, the
 * datasets first extended to `extent` events when shorter. */
static evr_status put_chunks(h5_writer *w, const evr_chunk_job *jobs, size_t nchunks, uint64_t at,
                             uint64_t extent, evr_error *err)
{
    herr_t r = 0;
    uint64_t bytes = 0;
    for (size_t k = 0; k < nchunks * (size_t)w->ncols; k++) bytes += jobs[k].dst_size;
    evr_status st = claim_room(w, bytes, err);
    if (st != EVR_OK) return st;
    if (extent < w->extent) extent = w->extent;
    H5E_BEGIN_TRY
    {
        hsize_t size[1] = {(hsize_t)extent};
        for (int c = 0; c < w->ncols && r >= 0; c++)
            if (extent != w->extent && H5Dset_extent(column_dataset(w, c), size) < 0) r = -1;
        for (size_t k = 0; k < nchunks && r >= 0; k++)
            for (int c = 0; c < w->ncols && r >= 0; c++) {
                const evr_chunk_job *j = &jobs[(size_t)c * nchunks + k];
                hsize_t offset[1] = {(hsize_t)(at + k * H5W_CHUNK)};
                r = H5Dwrite_chunk(column_dataset(w, c), H5P_DEFAULT, 0, offset, j->dst_size,
                                   j->dst);
            }
    }
    H5E_END_TRY;
    if (r < 0) return h5_fail(err, "cannot append events to", w->tmp);
    w->extent = extent;
    return EVR_OK;
}

static evr_status compress_failed(evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "hdf5 writer: out of memory compressing events");
    return EVR_ERR_NOMEM;
}

/* The full batch of set s from index at could not be stored: salvage tries again (the set's
 * compressed chunks stay as they are, since nothing is written after a failure). */
static void set_unstored(h5_writer *w, int s, uint64_t at)
{
    w->unstored = 1;
    w->unstored_set = s;
    w->unstored_at = at;
}

/* Waits for the batch in flight, if any, and stores it. */
static evr_status land_inflight(h5_writer *w, evr_error *err)
{
    if (!w->inflight) return EVR_OK;
    w->inflight = 0;
    if (!evr_chunk_pool_wait(w->pool)) return compress_failed(err);
    const uint64_t end = w->inflight_at + w->batch * H5W_CHUNK;
    evr_status st = put_chunks(w, w->set[1 - w->fill].jobs, w->batch, w->inflight_at, end, err);
    if (st != EVR_OK) set_unstored(w, 1 - w->fill, w->inflight_at);
    return st;
}

/* A full stage (batch chunks): compressed by the pool while the writer goes on; the batch in
 * flight before it lands meanwhile. */
static evr_status store_full(h5_writer *w, evr_error *err)
{
    const int was_inflight = w->inflight;
    const uint64_t prev_at = w->inflight_at;
    if (was_inflight && !evr_chunk_pool_wait(w->pool)) return compress_failed(err);
    h5_set *full = &w->set[w->fill];
    evr_chunk_pool_start(w->pool, full->jobs, make_jobs(w, full, w->batch, w->batch, 0));
    w->inflight = 1;
    w->inflight_at = w->written;
    w->written += w->batch * H5W_CHUNK;
    w->nstage = 0;
    w->tail_stored = 0;
    w->fill = 1 - w->fill; /* the landed batch's set stages next */
    if (was_inflight) {
        evr_status st = put_chunks(w, w->set[w->fill].jobs, w->batch, prev_at,
                                   prev_at + w->batch * H5W_CHUNK, err);
        if (st != EVR_OK) set_unstored(w, w->fill, prev_at);
        return st;
    }
    return EVR_OK;
}

/* Stores the full chunks of the stage and, with tail set, the partial chunk after them (when it
 * holds events not stored yet), then keeps only that partial chunk's events in the stage; the
 * batch in flight lands first. */
static evr_status store(h5_writer *w, int tail, evr_error *err)
{
    size_t nfull = w->nstage / H5W_CHUNK, rest = w->nstage % H5W_CHUNK;
    size_t nchunks, njobs;
    uint64_t done = nfull ? 0 : w->tail_stored; /* events of the partial chunk on file */
    evr_status st = land_inflight(w, err);
    if (st != EVR_OK) return st;
    if (!(tail && rest > done)) tail = 0;
    nchunks = nfull + (tail ? 1 : 0);
    if (nchunks == 0) return EVR_OK;
    /* nchunks <= batch: flush() finds the stage less than full (write() stores a full one at once) */
    h5_set *set = &w->set[w->fill];
    njobs = make_jobs(w, set, nchunks, nfull, rest);
    if (!evr_chunk_pool_run(w->pool, set->jobs, njobs)) return compress_failed(err);
    st = put_chunks(w, set->jobs, nchunks, w->written,
                    w->written + nfull * H5W_CHUNK + (tail ? rest : 0), err);
    if (st != EVR_OK) return st;
    if (nfull) {
        w->written += nfull * H5W_CHUNK;
        memmove(set->stage, set->stage + nfull * H5W_CHUNK, rest * sizeof *set->stage);
        w->nstage = rest;
        w->tail_stored = 0;
    }
    if (tail) w->tail_stored = rest;
    return EVR_OK;
}

/* Stores every staged event and appends the ms_to_idx entries computed so far. */
static evr_status drain(h5_writer *w, evr_error *err)
{
    herr_t r = 0;
    evr_status st = store(w, 1, err);
    if (st == EVR_OK) st = claim_room(w, w->nms * sizeof *w->ms, err);
    if (st != EVR_OK) return st;
    H5E_BEGIN_TRY
    {
        if (w->nms && append(w->ds_ms, H5T_NATIVE_UINT64, w->ms, w->ms_written, w->nms) < 0) r = -1;
    }
    H5E_END_TRY;
    if (r < 0) return h5_fail(err, "cannot append events to", w->tmp);
    w->ms_written += w->nms;
    w->nms = 0;
    return EVR_OK;
}

/* Keeps the k events staged before one the writer refuses (their time order ends at last_t) and
 * returns st. */
static evr_status stop_staging(h5_writer *w, size_t k, int64_t last_t, evr_status st)
{
    w->nstage += k;
    w->total += k;
    w->last_t = last_t;
    w->have_last = 1;
    return st;
}

/* An event as staged: p 0 or 1. */
static void stage_event(evr_event *d, const evr_event *e)
{
    d->t = e->t;
    d->x = e->x;
    d->y = e->y;
    d->p = e->p ? 1 : 0;
    d->id = e->id;
}

/* Parallel staging of m events (m >= 2) after a first one staged alone: part k checks and copies
 * its share of events 1 .. m - 1, each against the one before, and lists the millisecond
 * boundaries that fall between them (ms_to_idx's entries: the index of the first event at or
 * after the boundary). A part that finds an event out of order or out of range says so (bad);
 * the writer then stages the slice alone, which stops at the first such event. */
typedef struct {
    const evr_event *ev;
    evr_event *dst;
    size_t m;
    uint64_t base; /* dataset index of ev[0] */
    int t32;
    struct stage_part {
        uint64_t *ms;
        size_t nms, cap;
        int bad;
    } part[H5W_STAGE_PARTS];
} stage_job;

static void stage_part(void *ctx, int k, int thread)
{
    stage_job *j = ctx;
    struct stage_part *p = &j->part[k];
    size_t a, b;
    (void)thread;
    evr_par_share(j->m - 1, H5W_STAGE_PARTS, k, &a, &b); /* of events 1 .. m - 1 */
    a++;
    b++;
    p->nms = 0;
    p->bad = 0;
    for (size_t i = a; i < b; i++) {
        const evr_event *e = &j->ev[i];
        const int64_t prev = j->ev[i - 1].t;
        if (e->t < prev || (j->t32 && (uint64_t)e->t > UINT32_MAX)) {
            p->bad = 1;
            return;
        }
        /* boundaries B * 1000 in (prev, t]: this event is the first at or after them */
        for (int64_t next = (prev >= 0 ? prev / 1000 + 1 : 0) * 1000; e->t >= next; next += 1000) {
            if (p->nms == p->cap) {
                size_t cap = p->cap ? p->cap * 2 : 256;
                uint64_t *q = realloc(p->ms, cap * sizeof *q);
                if (!q) {
                    p->bad = 1;
                    return;
                }
                p->ms = q;
                p->cap = cap;
            }
            p->ms[p->nms++] = j->base + i;
        }
        stage_event(&j->dst[i], e);
    }
}

/* Stages ev[1 .. m) on the pool after ev[0] was staged (w->total, w->next_ms: as before ev[0]
 * was counted, ms entries up to ev[0] pushed). Returns 1 when done (w->total and the rest of the
 * stage's counts are the caller's to move on), 0 when a part found an event the serial path must
 * report (nothing more staged), -1 when out of memory. */
static int stage_parallel(h5_writer *w, const evr_event *ev, size_t m, evr_event *dst)
{
    stage_job j;
    int ok = 1, r = 1;
    memset(&j, 0, sizeof j);
    j.ev = ev;
    j.dst = dst;
    j.m = m;
    j.base = w->total;
    j.t32 = w->t32;
    evr_par_pool_run(w->stage_pool, H5W_STAGE_PARTS, stage_part, &j);
    size_t entries = 0;
    for (int k = 0; k < H5W_STAGE_PARTS; k++) {
        ok &= !j.part[k].bad;
        entries += j.part[k].nms;
    }
    if (!ok) r = 0;
    else if (!reserve_ms(w, entries)) r = -1; /* before any entry: the index stays whole */
    for (int k = 0; r > 0 && k < H5W_STAGE_PARTS; k++) {
        if (j.part[k].nms)
            memcpy(w->ms + w->nms, j.part[k].ms,
                   j.part[k].nms * sizeof *w->ms); /* ms NULL when none */
        w->nms += j.part[k].nms;
        w->next_ms += j.part[k].nms;
    }
    for (int k = 0; k < H5W_STAGE_PARTS; k++) free(j.part[k].ms);
    return r;
}

/* Stages ev[from .. to) one by one (dataset index w->total + k for ev[k]); *last_t is the time of
 * the event before. On a refused event, keeps those before it (stop_staging) and says why. */
static evr_status stage_serial(h5_writer *w, const evr_event *ev, evr_event *dst, size_t from,
                               size_t to, int64_t *last_t, evr_error *err)
{
    /* the first millisecond boundary not passed yet (ms entries stay below 2^63 / 1000 as long
     * as timestamps are int64) */
    int64_t next_ms_t = (int64_t)w->next_ms * 1000;
    for (size_t k = from; k < to; k++) {
        const evr_event *e = &ev[k];
        if (e->t < *last_t) {
            snprintf(err->msg, sizeof err->msg,
                     "hdf5 writer: events out of time order (%" PRId64 " us after %" PRId64 " us)",
                     e->t, *last_t);
            return stop_staging(w, k, *last_t, EVR_ERR_ARG);
        }
        if (w->t32 && (uint64_t)e->t > UINT32_MAX) {
            snprintf(err->msg, sizeof err->msg,
                     "hdf5 writer: timestamp %" PRId64 " us outside events/t's uint32 range", e->t);
            return stop_staging(w, k, *last_t, EVR_ERR_ARG);
        }
        *last_t = e->t;
        /* every millisecond boundary up to this event starts here */
        while (e->t >= next_ms_t) {
            if (!push_ms(w, w->total + k)) {
                snprintf(err->msg, sizeof err->msg, "hdf5 writer: out of memory");
                return stop_staging(w, k, *last_t, EVR_ERR_NOMEM);
            }
            next_ms_t += 1000;
        }
        stage_event(&dst[k], e);
    }
    return EVR_OK;
}

static evr_status h5_write(evr_event_writer *base, const evr_event *ev, size_t n, evr_error *err)
{
    h5_writer *w = (h5_writer *)base;
    while (n > 0) {
        size_t m = w->cap_stage - w->nstage;
        evr_event *dst = w->set[w->fill].stage + w->nstage;
        int64_t last_t = w->have_last ? w->last_t : ev[0].t;
        evr_status st;
        if (m > n) m = n;
        /* the first event alone (it continues the order and the ms index), the rest on the pool
         * when there are enough of them */
        const size_t first = m >= H5W_STAGE_MIN ? 1 : m;
        if ((st = stage_serial(w, ev, dst, 0, first, &last_t, err)) != EVR_OK) return st;
        if (first < m) {
            const int r = stage_parallel(w, ev, m, dst);
            if (r < 0) {
                snprintf(err->msg, sizeof err->msg, "hdf5 writer: out of memory");
                return stop_staging(w, 1, last_t, EVR_ERR_NOMEM);
            }
            if (r > 0) last_t = ev[m - 1].t;
            else if ((st = stage_serial(w, ev, dst, first, m, &last_t, err)) != EVR_OK) return st;
        }
        w->nstage += m;
        w->total += m;
        w->last_t = last_t;
        w->have_last = 1;
        ev += m;
        n -= m;
        if (w->nstage == w->cap_stage) {
            if ((st = store_full(w, err)) != EVR_OK) return st;
        }
    }
    return EVR_OK;
}

/* Full chunks only: see the top of the file. */
static evr_status h5_flush(evr_event_writer *base, evr_error *err)
{
    h5_writer *w = (h5_writer *)base;
    herr_t r;
    evr_status st = store(w, 0, err);
    if (st == EVR_OK) st = claim_room(w, 0, err);
    if (st != EVR_OK) return st;
    H5E_BEGIN_TRY { r = H5Fflush(w->file, H5F_SCOPE_GLOBAL); }
    H5E_END_TRY;
    if (r < 0) return h5_fail(err, "cannot flush", w->tmp);
    return EVR_OK;
}

static void h5_abort(evr_event_writer *base)
{
    h5_writer *w = (h5_writer *)base;
    close_all(w);
    remove(w->tmp);
    free_writer(w);
}

/* Closes the file and publishes it under its final name; frees the writer whatever the result
 * (removing the file when that fails). */
static evr_status close_publish(h5_writer *w, evr_error *err)
{
    evr_status st = EVR_OK;
    herr_t r = 0;
    H5E_BEGIN_TRY
    {
        /* closing the datasets first lets H5Fclose really close the file */
        hid_t *ids[] = {&w->ds_x, &w->ds_y, &w->ds_t, &w->ds_p, &w->ds_id, &w->ds_ms, &w->group};
        for (size_t i = 0; i < sizeof ids / sizeof ids[0]; i++) {
            if (*ids[i] >= 0 && (i == 6 ? H5Gclose(*ids[i]) : H5Dclose(*ids[i])) < 0) r = -1;
            *ids[i] = -1;
        }
        if (H5Fclose(w->file) < 0) r = -1;
        w->file = -1;
    }
    H5E_END_TRY;
    if (r < 0) st = h5_fail(err, "cannot complete", w->tmp);
    else if (evr_file_publish(w->tmp, w->path) != 0) {
        snprintf(err->msg, sizeof err->msg, "hdf5 writer: cannot complete %s: %s", w->path,
                 strerror(errno));
        st = EVR_ERR_IO;
    }
    if (st != EVR_OK) {
        close_all(w);
        remove(w->tmp);
    }
    free_writer(w);
    return st;
}

static evr_status h5_finish(evr_event_writer *base, int64_t duration_us, evr_error *err)
{
    h5_writer *w = (h5_writer *)base;
    evr_status st = EVR_OK;
    herr_t r = 0;
    /* entries up to ceil(duration / 1 ms) inclusive (more if events run past the duration) */
    uint64_t last = duration_us > 0 ? (uint64_t)((duration_us + 999) / 1000) : 0;
    while (w->next_ms <= last)
        if (!push_ms(w, w->total)) {
            snprintf(err->msg, sizeof err->msg, "hdf5 writer: out of memory");
            st = EVR_ERR_NOMEM;
            goto fail;
        }
    st = drain(w, err);
    if (st != EVR_OK) goto fail;
    H5E_BEGIN_TRY
    {
        int8_t complete = 1;
        r = write_scalar_attr(w->file, "complete", H5T_STD_I8LE, H5T_NATIVE_INT8, &complete);
    }
    H5E_END_TRY;
    if (r < 0) {
        st = h5_fail(err, "cannot complete", w->tmp);
        goto fail;
    }
    return close_publish(w, err);
fail:
    close_all(w);
    remove(w->tmp);
    free_writer(w);
    return st;
}

/* Stores everything staged or in flight (again, where a store failed), cuts the datasets to the
 * first `events` events and ms_to_idx to its entries within them, and completes the file with
 * its attribute complete at 0. */
static evr_status h5_salvage(evr_event_writer *base, uint64_t events, int64_t duration_us,
                             evr_error *err)
{
    h5_writer *w = (h5_writer *)base;
    evr_status st = EVR_OK;
    herr_t r = 0;
    size_t keep_ms = 0;
    (void)duration_us;
    if (events > w->total) {
        snprintf(err->msg, sizeof err->msg, "hdf5 writer: cannot keep %llu events of %s",
                 (unsigned long long)events, w->path);
        st = EVR_ERR_IO;
        goto fail;
    }
    if (w->inflight) {
        w->inflight = 0;
        if (!evr_chunk_pool_wait(w->pool)) st = compress_failed(err);
        else
            st = put_chunks(w, w->set[1 - w->fill].jobs, w->batch, w->inflight_at,
                            w->inflight_at + w->batch * H5W_CHUNK, err);
    }
    if (st == EVR_OK && w->unstored)
        st = put_chunks(w, w->set[w->unstored_set].jobs, w->batch, w->unstored_at,
                        w->unstored_at + w->batch * H5W_CHUNK, err);
    if (st == EVR_OK) st = store(w, 1, err);
    if (st == EVR_OK) st = claim_room(w, w->nms * sizeof *w->ms, err);
    if (st != EVR_OK) goto fail;
    /* ms_to_idx[i] is the first event at or after i ms: right for the first `events` events too
     * while it is at most `events` (entries only grow) */
    while (keep_ms < w->nms && w->ms[keep_ms] <= events) keep_ms++;
    H5E_BEGIN_TRY
    {
        hsize_t size[1] = {(hsize_t)events};
        int8_t complete = 0;
        for (int c = 0; c < w->ncols && r >= 0; c++)
            if (H5Dset_extent(column_dataset(w, c), size) < 0) r = -1;
        if (r >= 0 && keep_ms &&
            append(w->ds_ms, H5T_NATIVE_UINT64, w->ms, w->ms_written, keep_ms) < 0)
            r = -1;
        if (r >= 0)
            r = write_scalar_attr(w->file, "complete", H5T_STD_I8LE, H5T_NATIVE_INT8, &complete);
    }
    H5E_END_TRY;
    if (r < 0) {
        st = h5_fail(err, "cannot complete", w->tmp);
        goto fail;
    }
    w->nms = 0;
    return close_publish(w, err);
fail:
    close_all(w);
    remove(w->tmp);
    free_writer(w);
    return st;
}

evr_status evr_h5_writer_open(const char *path, const evr_writer_meta *meta, evr_event_writer **out,
                              evr_error *err)
{
    h5_writer *w;
    herr_t r = -1;
    const char *what = "cannot create";

    *out = NULL;
    /* A file whose closing failed (a full disk, an I/O error) is left half closed by HDF5, and
     * the library's own clean-up at exit then crashes on it: the process ends without that
     * clean-up (the writer closes its files itself). Only before HDF5's first call in the
     * process does this take effect. */
    H5dont_atexit();
    if (!path || !*path || !meta) {
        snprintf(err->msg, sizeof err->msg, "hdf5 writer: no path or metadata given");
        return EVR_ERR_ARG;
    }
    w = calloc(1, sizeof *w);
    if (w) {
        /* a batch gives every thread a chunk of each column; about 40 MB with 16 threads */
        int threads = evr_par_threads(H5W_MAX_THREADS);
        size_t room = 0;
        w->file = w->group = w->ds_x = w->ds_y = w->ds_t = w->ds_p = w->ds_id = w->ds_ms = -1;
        w->ncols = meta->event_ids ? H5W_COLUMNS : H5W_COLUMNS - 1;
        w->t32 = meta->max_t_us > 0 && meta->max_t_us <= (int64_t)UINT32_MAX;
        w->batch = threads < H5W_MIN_BATCH ? H5W_MIN_BATCH : (size_t)threads;
        w->cap_stage = w->batch * H5W_CHUNK;
        for (int c = 0; c < w->ncols; c++) room += column_room(w, c);
        w->path = strdup(path);
        w->tmp = evr_file_tmp_name(path);
        for (int i = 0; i < 2; i++) {
            w->set[i].stage = malloc(w->cap_stage * sizeof *w->set[i].stage);
            w->set[i].jobs = malloc(H5W_COLUMNS * w->batch * sizeof *w->set[i].jobs);
            w->set[i].zbuf = malloc(room);
        }
        w->pool = evr_chunk_pool_new(threads, H5W_CHUNK * sizeof(int64_t));
        w->stage_pool = evr_par_pool_new(evr_par_threads(H5W_STAGE_THREADS));
    }
    if (!w || !w->path || !w->tmp || !w->set[0].stage || !w->set[0].jobs || !w->set[0].zbuf ||
        !w->set[1].stage || !w->set[1].jobs || !w->set[1].zbuf || !w->pool || !w->stage_pool) {
        if (w) free_writer(w);
        snprintf(err->msg, sizeof err->msg, "hdf5 writer: out of memory");
        return EVR_ERR_NOMEM;
    }

    H5E_BEGIN_TRY
    {
        int32_t width = meta->width, height = meta->height;
        int64_t zero = 0;
        int8_t incomplete = 0;
        w->file = evr_h5_create_reproducible(w->tmp);
        if (w->file >= 0) {
            hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE);
            what = "cannot lay out";
            if (gcpl >= 0 && H5Pset_obj_track_times(gcpl, 0) >= 0)
                w->group = H5Gcreate2(w->file, "events", H5P_DEFAULT, gcpl, H5P_DEFAULT);
            if (gcpl >= 0) H5Pclose(gcpl);
        }
        if (w->group >= 0) w->ds_x = make_extendible(w->group, "x", H5T_STD_U16LE, H5W_CHUNK);
        if (w->ds_x >= 0) w->ds_y = make_extendible(w->group, "y", H5T_STD_U16LE, H5W_CHUNK);
        if (w->ds_y >= 0)
            w->ds_t =
                make_extendible(w->group, "t", w->t32 ? H5T_STD_U32LE : H5T_STD_I64LE, H5W_CHUNK);
        if (w->ds_t >= 0) w->ds_p = make_extendible(w->group, "p", H5T_STD_I8LE, H5W_CHUNK);
        int laid_out = w->ds_p >= 0;
        if (laid_out && meta->event_ids) /* events/id and the /instances that name them */
            laid_out =
                (w->ds_id = make_extendible(w->group, "id", H5T_STD_U16LE, H5W_CHUNK)) >= 0 &&
                evr_h5_write_instances(w->file, meta->inst_node, meta->inst_mesh,
                                       meta->num_instances) >= 0;
        if (laid_out) w->ds_ms = make_extendible(w->file, "ms_to_idx", H5T_STD_U64LE, H5W_MS_CHUNK);
        if (w->ds_ms >= 0 &&
            write_scalar_dataset(w->file, "t_offset", H5T_STD_I64LE, H5T_NATIVE_INT64, &zero) >=
                0 &&
            write_scalar_attr(w->file, "width", H5T_STD_I32LE, H5T_NATIVE_INT32, &width) >= 0 &&
            write_scalar_attr(w->file, "height", H5T_STD_I32LE, H5T_NATIVE_INT32, &height) >= 0 &&
            write_scalar_attr(w->file, "complete", H5T_STD_I8LE, H5T_NATIVE_INT8, &incomplete) >=
                0 &&
            write_string_attr(w->file, "config", meta->config_json ? meta->config_json : "{}") >= 0)
            r = H5Fflush(w->file, H5F_SCOPE_GLOBAL);
    }
    H5E_END_TRY;
    if (r < 0) {
        evr_status st = h5_fail(err, what, w->tmp);
        int created = w->file >= 0;
        close_all(w);
        if (created) remove(w->tmp);
        free_writer(w);
        return st;
    }
    w->base.write = h5_write;
    w->base.flush = h5_flush;
    w->base.finish = h5_finish;
    w->base.abort = h5_abort;
    w->base.salvage = h5_salvage;
    *out = &w->base;
    return EVR_OK;
}

const evr_event_format evr_format_h5 = {
    "h5",        "hdf5", "events.h5", evr_h5_writer_open, "HDF5: events/x, y, t, p and ms_to_idx",
    ".h5 .hdf5", 1};
