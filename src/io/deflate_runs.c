/* Runs as one fixed-Huffman deflate block (see deflate_runs.h). The codes are RFC 1951's fixed
 * ones (section 3.2.6), written bit-reversed into the LSB-first bit stream. */
#include "io/deflate_runs.h"

#include <stdint.h>
#include <string.h>

/* Lengths 3 .. 258 of a match: the symbol's base and its extra bits (RFC 1951, 3.2.5). */
static const uint16_t len_base[29] = {3,  4,  5,  6,   7,   8,   9,   10,  11, 13,
                                      15, 17, 19, 23,  27,  31,  35,  43,  51, 59,
                                      67, 83, 99, 115, 131, 163, 195, 227, 258};
static const uint8_t len_extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                      2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};

typedef struct {
    unsigned char *p, *end;
    uint64_t acc; /* bits not yet written, the first in bit 0 */
    int nbits;
    int full; /* dst ran out of room */
} bit_writer;

static inline void put_bits(bit_writer *w, uint32_t bits, int n)
{
    w->acc |= (uint64_t)bits << w->nbits;
    w->nbits += n;
    while (w->nbits >= 8) {
        if (w->p == w->end) {
            w->full = 1;
            w->nbits = 0;
            return;
        }
        *w->p++ = (unsigned char)w->acc;
        w->acc >>= 8;
        w->nbits -= 8;
    }
}

static uint32_t reversed(uint32_t code, int n)
{
    uint32_t r = 0;
    for (int i = 0; i < n; i++) r |= ((code >> i) & 1u) << (n - 1 - i);
    return r;
}

/* The fixed literal/length code of every symbol, bit-reversed, and its length. */
typedef struct {
    uint16_t code[286];
    uint8_t len[286];
} fixed_codes;

static void make_fixed_codes(fixed_codes *c)
{
    for (int s = 0; s < 286; s++) {
        uint32_t code;
        int n;
        if (s < 144) {
            code = 0x30u + (uint32_t)s;
            n = 8;
        } else if (s < 256) {
            code = 0x190u + (uint32_t)(s - 144);
            n = 9;
        } else if (s < 280) {
            code = (uint32_t)(s - 256);
            n = 7;
        } else {
            code = 0xc0u + (uint32_t)(s - 280);
            n = 8;
        }
        c->code[s] = (uint16_t)reversed(code, n);
        c->len[s] = (uint8_t)n;
    }
}

static inline void put_symbol(bit_writer *w, const fixed_codes *c, int s)
{
    put_bits(w, c->code[s], c->len[s]);
}

/* A copy of the byte before, len (3 .. 258) times. */
static inline void put_match(bit_writer *w, const fixed_codes *c, int len)
{
    int i = 28;
    while (len_base[i] > len) i--;
    put_symbol(w, c, 257 + i);
    put_bits(w, (uint32_t)(len - len_base[i]), len_extra[i]);
    put_bits(w, 0, 5); /* distance 1: code 0 of the fixed 5-bit distance codes */
}

/* Bytes equal to b from src[i] on, at most n - i. */
static inline size_t run_from(const unsigned char *src, size_t i, size_t n, unsigned char b)
{
    const uint64_t all = 0x0101010101010101ull * b;
    size_t j = i;
    while (j + 8 <= n) {
        uint64_t v;
        memcpy(&v, src + j, 8);
        if (v != all) break;
        j += 8;
    }
    while (j < n && src[j] == b) j++;
    return j - i;
}

size_t evr_deflate_runs(const unsigned char *src, size_t n, unsigned char *dst, size_t room)
{
    bit_writer w = {dst, dst + room, 0, 0, 0};
    fixed_codes c; /* made per call: a few thousand operations against a chunk's scan */
    size_t i = 0;
    make_fixed_codes(&c);
    put_bits(&w, 1, 1); /* BFINAL */
    put_bits(&w, 1, 2); /* BTYPE 01: fixed Huffman codes */
    while (i < n && !w.full) {
        const unsigned char b = src[i];
        put_symbol(&w, &c, b);
        size_t r = run_from(src, i + 1, n, b);
        i += 1 + r;
        while (r >= 3) {
            const size_t len = r > 258 ? 258 : r;
            put_match(&w, &c, (int)len);
            r -= len;
        }
        while (r--) put_symbol(&w, &c, b);
    }
    put_symbol(&w, &c, 256);                       /* end of block */
    if (w.nbits > 0) put_bits(&w, 0, 8 - w.nbits); /* to the byte */
    return w.full ? 0 : (size_t)(w.p - dst);
}

size_t evr_deflate_repeats(const unsigned char *src, size_t n)
{
    size_t r = 0;
    for (size_t i = 1; i < n; i++) r += src[i] == src[i - 1];
    return r;
}
