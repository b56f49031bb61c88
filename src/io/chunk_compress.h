/* Chunks of 1-D datasets compressed the way HDF5's filter pipeline does it with the shuffle and
 * deflate filters (H5Pset_shuffle, then H5Pset_deflate), so that they can be stored with
 * H5Dwrite_chunk and read by any HDF5 reader as if HDF5 had filtered them itself:
 *
 *   shuffle  the chunk's element bytes transposed: every element's first byte, then every
 *            element's second byte, ... (HDF5 leaves 1-byte elements as they are)
 *   deflate  a zlib stream (header and Adler-32 included), made by libdeflate at the given level;
 *            leading byte planes of nearly random bytes (at least 7 bits of entropy per byte,
 *            few runs) in stored blocks instead
 *
 * A chunk always holds the dataset's full chunk size; elements past the data (the last chunk of a
 * dataset whose length is not a multiple of it) are zero, HDF5's default fill value, which is
 * what HDF5 itself puts there.
 *
 * A pool of threads (a par_pool.h pool, each thread with a compressor of its own) compresses a
 * list of chunks in parallel; the calling thread works too, so a pool of one thread starts no
 * thread at all; evr_par_threads tells how many to ask for. The pool is owned by one writer at a
 * time. */
#ifndef EVR_IO_CHUNK_COMPRESS_H
#define EVR_IO_CHUNK_COMPRESS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    /* in */
    const void *src;    /* first element's bytes */
    size_t stride;      /* bytes from one element to the next in src */
    size_t elem_size;   /* bytes per element */
    size_t count;       /* elements taken from src (at most chunk_elems) */
    size_t chunk_elems; /* elements in a chunk: the rest is zero */
    int level;          /* libdeflate's compression level, 0 .. 12 */
    unsigned char *dst; /* room for evr_chunk_bound(chunk_elems * elem_size) bytes */
    /* out */
    size_t dst_size; /* compressed bytes */
    int ok;          /* 0: the compressor failed (out of memory) */
} evr_chunk_job;

typedef struct evr_chunk_pool evr_chunk_pool;

/* What one thread compresses with: room for a shuffled chunk of at most max_chunk_bytes, and a
 * compressor. NULL when out of memory. */
typedef struct evr_chunk_worker evr_chunk_worker;
evr_chunk_worker *evr_chunk_worker_new(size_t max_chunk_bytes);
void evr_chunk_worker_free(evr_chunk_worker *w); /* NULL is fine */

/* Bytes that the compressed form of a chunk of raw_bytes bytes can take at most. */
size_t evr_chunk_bound(size_t raw_bytes);

/* Compresses one chunk with worker w (made for at least chunk_elems * elem_size bytes). Returns
 * job->ok. */
int evr_chunk_compress(evr_chunk_job *job, evr_chunk_worker *w);

/* A pool of threads (the caller counted) for chunks of at most max_chunk_bytes raw bytes.
 * NULL when out of memory or when no thread can be started. */
evr_chunk_pool *evr_chunk_pool_new(int threads, size_t max_chunk_bytes);

/* Compresses jobs[0 .. n) and returns when all are done: 1 when every job succeeded. Jobs are
 * taken in order, so list the largest first. */
int evr_chunk_pool_run(evr_chunk_pool *pool, evr_chunk_job *jobs, size_t n);

/* The same in two steps: start hands the jobs to the pool's threads and returns at once (the
 * caller may do other work; jobs and their buffers must stay as they are); wait takes the jobs
 * not taken yet (all of them in a pool of one thread) and returns when all are done, 1 when
 * every job succeeded. One list at a time: start, then wait, before the next start. */
void evr_chunk_pool_start(evr_chunk_pool *pool, evr_chunk_job *jobs, size_t n);
int evr_chunk_pool_wait(evr_chunk_pool *pool);

int evr_chunk_pool_threads(const evr_chunk_pool *pool);

/* Stops the threads and frees the pool (NULL is fine). */
void evr_chunk_pool_free(evr_chunk_pool *pool);

#ifdef __cplusplus
}
#endif
#endif
