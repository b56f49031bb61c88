/* A deflate block (RFC 1951) made of runs only: every byte that differs from the one before it is
 * a literal, every run of a byte a literal and distance-1 matches, all in the fixed Huffman codes.
 * For byte planes that are mostly runs (the shuffled timestamps of a sorted event stream: their
 * high bytes constant, their low byte repeating the one before nine times in ten) it is an order
 * of magnitude faster than libdeflate's level 1, which still searches its hash table at every
 * position; any inflater reads it. */
#ifndef EVR_IO_DEFLATE_RUNS_H
#define EVR_IO_DEFLATE_RUNS_H

#include <stddef.h>

/* Writes src[0 .. n) as one final fixed-Huffman block to dst (at most room bytes). Returns the
 * bytes written, 0 when they do not fit. */
size_t evr_deflate_runs(const unsigned char *src, size_t n, unsigned char *dst, size_t room);

/* Of src[1 .. n), the bytes equal to the one before them. */
size_t evr_deflate_repeats(const unsigned char *src, size_t n);

#endif
