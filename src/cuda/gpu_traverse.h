/* Ray queries against the structure of gpu_bvh.h, written once for the host C compiler and
 * for nvcc (EVR_HD, no recursion, fixed-size stacks, no dynamically indexed arrays in the hot
 * loops except the stack).
 *
 *   evr_trace_closest  nearest hit of a world ray at normalized segment time f in [0, 1]
 *   evr_trace_any      whether anything lies between tnear and tfar (shadow rays)
 *
 * The answers are Embree's (cpu backend): the instance is the scene's instance index, the
 * primitive the original triangle index of its mesh, barycentrics (u, v) such that
 * p = (1-u-v) p0 + u p1 + v p2, t the distance along the world ray (in units of its direction,
 * unit for the camera's rays). The instance comes from the triangle record (plus its group's
 * instance_base): a group's tree holds the triangles of all its instances.
 *
 * Each moving group's transform is evaluated at the ray's time exactly as the CPU backend does
 * (evr_motion_eval of its track), inverted, and the ray moved into group space without
 * normalizing its direction, so t stays the world parameter (the static group's space is the
 * world: an identity transform, exact in float). A deforming group's triangles get their
 * vertices at the ray's time from the segment's vertex keys (evr_deform_lerp_in, what shading
 * reads too); a top-level leaf is a deforming group when its root is negative. Hits that a
 * material rules out (core/hit_filter.h: alpha MASK holes, single-sided back faces; each
 * triangle carries its mesh's filter bits) are passed over where they are met, and the search
 * goes on behind them (a shadow ray's too). Whether a scene has deforming groups or such meshes
 * at all is a constant of the search (`general`; on the device a bit of the kernel's LAYOUT,
 * EVR_GPU_TRACE_GENERAL): without them the search holds no trace of them. Any trace of them
 * in that code changed the eye's render kernel's registers and spills (a branch per group
 * entered, a call to a search of their own inside or after this one, even passing a
 * triangle's vertices by pointer instead of the record); so the CUDA kernels come in both
 * kinds, and the general kind checks each group it enters and, where the scene has filtered
 * meshes, each hit's filter bits, and searches a deforming group's tree out of line
 * (evr__blas_deform). One general kind for both keeps the number of kernel instantiations
 * (cuda_render.cu's compile time) as it was; a scene with deforming meshes but no filtered
 * ones pays a test of a null pointer per hit. One source serves both, inlined with the
 * constants folded (EVR__ALWAYS_INLINE), the node layout among them. Triangles are intersected
 * with the watertight test of Woop, Benthin and Wald (JCGT 2013): a ray through a shared edge
 * or vertex hits at least one of the triangles. Its edge functions must be evaluated without fused
 * multiply-adds (exactly antisymmetric): on the device through __fmul_rn/__fsub_rn, on the host
 * by the C compiler's default (ISO C mode, -ffp-contract=off); do not build this with
 * -ffast-math. Box tests widen their far distances by 1 + 2 gamma(3) (Ize 2013, pbrt), which
 * with boxes that contain their triangles exactly (see gpu_bvh.h) makes traversal conservative. */
#ifndef EVR_CUDA_GPU_TRAVERSE_H
#define EVR_CUDA_GPU_TRAVERSE_H

#include <math.h>
#include <stdint.h>
#include <string.h>
#include "core/hd.h"
#include "core/vec.h"
#include "core/motion.h"
#include "core/camera.h"
#include "core/render_scene.h"
#include "core/hit_filter.h"
#include "cuda/gpu_bvh.h"

typedef struct {
    float t, u, v;
    int instance;  /* scene instance index */
    uint32_t prim; /* triangle index in the instance's mesh */
} evr_gpu_hit;

#ifdef __CUDA_ARCH__
#define EVR__UNROLL _Pragma("unroll")
#else
#define EVR__UNROLL
#endif
/* the children of a CW8 node: EVR_NODE8_UNROLL of them per loop turn on the device. Not
 * unrolled: the traversal's code then fits the instruction cache better (H100, the 30 s eye:
 * kernels 1.46 s unrolled eight times, 1.22 s not; instruction fetch was 43% of the stalls) */
#ifndef EVR_NODE8_UNROLL
#define EVR_NODE8_UNROLL 1
#endif
#define EVR__PRAGMA(x) _Pragma(#x)
#define EVR__PRAGMA_UNROLL(n) EVR__PRAGMA(unroll n)
#ifdef __CUDA_ARCH__
#define EVR__NODE8_UNROLL EVR__PRAGMA_UNROLL(EVR_NODE8_UNROLL)
#define EVR__NO_UNROLL EVR__PRAGMA_UNROLL(1)
#else
#define EVR__NODE8_UNROLL
#define EVR__NO_UNROLL
#endif

/* The searches are inlined into each caller with what says deforming or not a constant (see the
 * top). */
#ifdef __CUDACC__
#define EVR__ALWAYS_INLINE __forceinline__
#else
#define EVR__ALWAYS_INLINE inline __attribute__((always_inline))
#endif

/* The searches' work counted, on the host only and only where EVR_TRAVERSE_STATS is defined
 * (tests/test_gpu_bvh.c's stats build: docs/benchmarks.md); otherwise no code at all */
#if defined(EVR_TRAVERSE_STATS) && !defined(__CUDACC__)
typedef struct {
    long top_nodes, groups, nodes, tris;
} evr_traverse_stats;
extern evr_traverse_stats evr_tstats;
#define EVR__STAT(field) (evr_tstats.field++)
#else
#define EVR__STAT(field) ((void)0)
#endif

/* 1 + 2 gamma(3), gamma(n) = n eps / (1 - n eps), eps = 2^-24 */
#define EVR__BOX_WIDEN 1.00000036f

/* ---- small helpers ---- */

EVR_HD static inline float evr__sel3(float x, float y, float z, int k)
{
    return k == 0 ? x : (k == 1 ? y : z);
}

/* 1/d, with |d| raised to 1e-18 first (no infinities, no 0 * inf in the slab test) */
EVR_HD static inline float evr__rcp_safe(float d)
{
    float a = fabsf(d) < 1e-18f ? (d < 0.0f ? -1e-18f : 1e-18f) : d;
    return 1.0f / a;
}

EVR_HD static inline int evr__msb(uint32_t x) /* x != 0 */
{
#ifdef __CUDA_ARCH__
    return 31 - __clz((int)x);
#else
    return 31 - __builtin_clz(x);
#endif
}

EVR_HD static inline int evr__popc(uint32_t x)
{
#ifdef __CUDA_ARCH__
    return __popc(x);
#else
    return __builtin_popcount(x);
#endif
}

EVR_HD static inline uint32_t evr__f2u(float f)
{
#ifdef __CUDA_ARCH__
    return __float_as_uint(f);
#else
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
#endif
}

EVR_HD static inline float evr__u2f(uint32_t u)
{
#ifdef __CUDA_ARCH__
    return __uint_as_float(u);
#else
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
#endif
}

/* a * b - c * d with each product rounded (no fused multiply-add): exactly antisymmetric */
EVR_HD static inline float evr__cross2(float a, float b, float c, float d)
{
#ifdef __CUDA_ARCH__
    return __fsub_rn(__fmul_rn(a, b), __fmul_rn(c, d));
#else
    return a * b - c * d;
#endif
}

/* a - s * b, the same way for every vertex */
EVR_HD static inline float evr__shear(float a, float s, float b)
{
#ifdef __CUDA_ARCH__
    return __fmaf_rn(-s, b, a);
#else
    return a - s * b;
#endif
}

/* ---- rays ---- */

typedef struct {
    float ox, oy, oz, dx, dy, dz;
    float ix, iy, iz; /* safe reciprocals of the direction */
    int kx, ky, kz;   /* watertight test: kz the dominant axis */
    float sx, sy, sz; /* its shear */
    int oct_inv;      /* CW8: 7 - octant of the direction */
} evr__tray;

EVR_HD static inline void evr__tray_init(evr__tray *r, evr_v3 o, evr_v3 d)
{
    float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z), dz;
    int kx, ky, kz, t;
    r->ox = o.x;
    r->oy = o.y;
    r->oz = o.z;
    r->dx = d.x;
    r->dy = d.y;
    r->dz = d.z;
    r->ix = evr__rcp_safe(d.x);
    r->iy = evr__rcp_safe(d.y);
    r->iz = evr__rcp_safe(d.z);
    kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    kx = kz == 2 ? 0 : kz + 1;
    ky = kx == 2 ? 0 : kx + 1;
    dz = evr__sel3(d.x, d.y, d.z, kz);
    if (dz < 0.0f) {
        t = kx;
        kx = ky;
        ky = t;
    } /* keeps the winding */
    r->kx = kx;
    r->ky = ky;
    r->kz = kz;
    r->sx = evr__sel3(d.x, d.y, d.z, kx) / dz;
    r->sy = evr__sel3(d.x, d.y, d.z, ky) / dz;
    r->sz = 1.0f / dz;
    r->oct_inv = 7 - ((d.x < 0.0f ? 1 : 0) | (d.y < 0.0f ? 2 : 0) | (d.z < 0.0f ? 4 : 0));
}

/* Slab test of a box given by its planes nearest to the ray's origin (n) and farthest from it (f)
 * on each axis: entry distance in *tn when the ray's [tnear, tfar] meets it. */
EVR_HD static inline int evr__slab(const evr__tray *r, float nx, float ny, float nz, float fx,
                                   float fy, float fz, float tnear, float tfar, float *tn)
{
    const float tnx = (nx - r->ox) * r->ix, tny = (ny - r->oy) * r->iy, tnz = (nz - r->oz) * r->iz;
    const float tfx = (fx - r->ox) * r->ix, tfy = (fy - r->oy) * r->iy, tfz = (fz - r->oz) * r->iz;
    /* fminf/fmaxf (one instruction each on the device): no NaN can occur here (finite planes,
     * origin and reciprocals), where they equal a compare and select but for the sign of a zero;
     * widened after the minimum: a product's rounding is monotone, so the same value as each
     * widened before it, in one multiplication */
    float a = fmaxf(fmaxf(tnx, tny), fmaxf(tnz, tnear));
    float b = fminf(fminf(fminf(tfx, tfy), tfz) * EVR__BOX_WIDEN, tfar);
    *tn = a;
    return a <= b;
}

/* Slab test of the box [lo, hi]: entry distance in *tn when the ray's [tnear, tfar] meets it. */
EVR_HD static inline int evr__box(const evr__tray *r, float lox, float loy, float loz, float hix,
                                  float hiy, float hiz, float tnear, float tfar, float *tn)
{
    return evr__slab(r, r->ix >= 0.0f ? lox : hix, r->iy >= 0.0f ? loy : hiy,
                     r->iz >= 0.0f ? loz : hiz, r->ix >= 0.0f ? hix : lox,
                     r->iy >= 0.0f ? hiy : loy, r->iz >= 0.0f ? hiz : loz, tnear, tfar, tn);
}

/* Watertight ray/triangle test (two-sided): t in (tnear, tfar], barycentrics as Embree's. */
EVR_HD static inline int evr__tri(const evr__tray *r, const evr_gpu_tri *tri, float tnear,
                                  float tfar, float *t_out, float *u_out, float *v_out)
{
    float a0 = tri->v0[0] - r->ox, a1 = tri->v0[1] - r->oy, a2 = tri->v0[2] - r->oz;
    float b0 = tri->v1[0] - r->ox, b1 = tri->v1[1] - r->oy, b2 = tri->v1[2] - r->oz;
    float c0 = tri->v2[0] - r->ox, c1 = tri->v2[1] - r->oy, c2 = tri->v2[2] - r->oz;
    float akz = evr__sel3(a0, a1, a2, r->kz), bkz = evr__sel3(b0, b1, b2, r->kz),
          ckz = evr__sel3(c0, c1, c2, r->kz);
    float ax = evr__shear(evr__sel3(a0, a1, a2, r->kx), r->sx, akz);
    float ay = evr__shear(evr__sel3(a0, a1, a2, r->ky), r->sy, akz);
    float bx = evr__shear(evr__sel3(b0, b1, b2, r->kx), r->sx, bkz);
    float by = evr__shear(evr__sel3(b0, b1, b2, r->ky), r->sy, bkz);
    float cx = evr__shear(evr__sel3(c0, c1, c2, r->kx), r->sx, ckz);
    float cy = evr__shear(evr__sel3(c0, c1, c2, r->ky), r->sy, ckz);
    float u = evr__cross2(cx, by, cy, bx); /* weight of v0 */
    float v = evr__cross2(ax, cy, ay, cx); /* weight of v1 */
    float w = evr__cross2(bx, ay, by, ax); /* weight of v2 */
    float det, tt, adet;
    if (u == 0.0f || v == 0.0f || w == 0.0f) { /* on an edge in float: decide exactly */
        u = (float)((double)cx * (double)by - (double)cy * (double)bx);
        v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
        w = (float)((double)bx * (double)ay - (double)by * (double)ax);
    }
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return 0;
    det = u + v + w;
    if (det == 0.0f) return 0;
    tt = u * (r->sz * akz) + v * (r->sz * bkz) + w * (r->sz * ckz);
    adet = fabsf(det);
    if (det < 0.0f) tt = -tt;
    if (!(tt > tnear * adet && tt <= tfar * adet)) return 0;
    *t_out = tt / adet;
    *u_out = v / det;
    *v_out = w / det;
    return 1;
}

typedef struct {
    uint32_t a, b;
} evr__stack_entry;

/* What a bottom-level search reports besides the distance. */
typedef struct {
    uint32_t prim;
    int32_t inst; /* the triangle's instance field */
    float u, v;
} evr__tri_hit;

/* A deforming group's triangles and where their vertices are at the ray's time: the group's
 * deform view and the key interval of the time (evr_key_interval), found once per search. */
typedef struct {
    const evr_gpu_dtri *tris;
    evr_deform_view view;
    int a;    /* key interval */
    float fr; /* and the fraction in it */
} evr__deform_src;

/* Leaf item i against the ray: a rigid triangle of tris, or with ds a deforming one. */
EVR_HD static EVR__ALWAYS_INLINE int evr__leaf_tri(const evr_gpu_tri *tris,
                                                   const evr__deform_src *ds, uint32_t i,
                                                   const evr__tray *r, float tnear, float tfar,
                                                   float *t, float *u, float *v)
{
    if (ds) { /* the same test of a record of its vertices at the ray's time */
        const evr_gpu_dtri *d = &ds->tris[i];
        evr_gpu_tri at;
        float *p[3];
        int k;
        p[0] = at.v0;
        p[1] = at.v1;
        p[2] = at.v2;
        for (k = 0; k < 3; k++) {
            const evr_v3 q =
                evr_deform_lerp_in(&ds->view, ds->view.positions, d->v[k], ds->a, ds->fr);
            p[k][0] = q.x;
            p[k][1] = q.y;
            p[k][2] = q.z;
        }
        return evr__tri(r, &at, tnear, tfar, t, u, v);
    }
    return evr__tri(r, &tris[i], tnear, tfar, t, u, v);
}

/* What the general search needs to rule out a hit (core/hit_filter.h): the scene, the group's
 * instance base, the world ray's direction and time, whether it is a shadow ray (any), the
 * filter bits that count for it (a shadow ray sees back faces: EVR_FILTER_MASK only) and, for a
 * deforming group, its mesh's bits among them. */
typedef struct {
    const evr_render_scene *rs;
    int32_t instance_base;
    evr_v3 dir;
    float f;
    int shadow;
    uint32_t bits, dbits;
} evr__filter_src;

/* core/hit_filter.h's test, out of line on the device: inlined into each of the search's leaf
 * loops it made the general kernels' traversal three times longer (PTX), and the instruction
 * cache is what the traversal stalls on (cuda_trace.cuh). fs by address: what it alone reads
 * stays in memory, not in the search's registers. */
#ifdef __CUDACC__
#define EVR__NOINLINE __noinline__
#else
#define EVR__NOINLINE __attribute__((noinline))
#endif
EVR_HD static EVR__NOINLINE int evr__hit_filtered(const evr__filter_src *fs, int inst,
                                                  uint32_t prim, float u, float v)
{
    return evr_hit_filtered(fs->rs, inst, prim, u, v, fs->dir, 0, fs->f, fs->shadow);
}

/* Whether the hit at (u, v) of leaf item i is ruled out; never without fs (the rigid search,
 * where fs is a constant NULL and this folds away). A triangle whose mesh has no filter bits
 * (evr_gpu_tri.filter) costs a test of a field already loaded. */
EVR_HD static EVR__ALWAYS_INLINE int evr__leaf_filtered(const evr_gpu_tri *tris,
                                                        const evr__deform_src *ds,
                                                        const evr__filter_src *fs, uint32_t i,
                                                        float u, float v)
{
    int inst;
    uint32_t prim;
    if (!fs) return 0;
    if (ds) {
        if (!fs->dbits) return 0;
        inst = fs->instance_base;
        prim = ds->tris[i].prim;
    } else {
        if (!(tris[i].filter & fs->bits)) return 0;
        inst = fs->instance_base + tris[i].instance;
        prim = tris[i].prim;
    }
    return evr__hit_filtered(fs, inst, prim, u, v);
}

/* The triangle and instance fields of a leaf item that was hit (read only then). */
EVR_HD static EVR__ALWAYS_INLINE void
evr__leaf_hit(const evr_gpu_tri *tris, const evr__deform_src *ds, uint32_t i, evr__tri_hit *th)
{
    if (ds) {
        th->prim = ds->tris[i].prim;
        th->inst = 0; /* the group's one instance */
        return;
    }
    th->prim = tris[i].prim;
    th->inst = tris[i].instance;
}

/* ---- BVH4 ---- */

#define EVR__CSWAP(i, j)      \
    do {                      \
        if (ct[j] < ct[i]) {  \
            float t_ = ct[i]; \
            int c_ = ci[i];   \
            ct[i] = ct[j];    \
            ci[i] = ci[j];    \
            ct[j] = t_;       \
            ci[j] = c_;       \
        }                     \
    } while (0)

/* Children of a BVH4 node that the ray meets, inner ones sorted by entry distance into
 * (ci, ct) (misses at +inf); leaves are handed back through leaf_first/leaf_count in slot
 * order (count 0: none). */
EVR_HD static inline void evr__node4(const evr_gpu_node4 *n, const evr__tray *r, float tnear,
                                     float tfar, int ci[4], float ct[4], int leaf_first[4],
                                     uint32_t leaf_count[4])
{
    int i;
    EVR__UNROLL
    for (i = 0; i < 4; i++) {
        float tn;
        int c = n->child[i];
        uint32_t cnt = n->count[i];
        int hit = c >= 0 && evr__box(r, n->lo_x[i], n->lo_y[i], n->lo_z[i], n->hi_x[i], n->hi_y[i],
                                     n->hi_z[i], tnear, tfar, &tn);
        ci[i] = c;
        ct[i] = hit && cnt == 0 ? tn : INFINITY;
        leaf_first[i] = c;
        leaf_count[i] = hit ? cnt : 0u;
    }
    EVR__CSWAP(0, 1);
    EVR__CSWAP(2, 3);
    EVR__CSWAP(0, 2);
    EVR__CSWAP(1, 3);
    EVR__CSWAP(1, 2);
}

/* Nearest (any != 0: first) triangle of one group in (tnear, *tfar]; shrinks *tfar. Uses the
 * stack above sp0. The triangles are tris, or with ds a deforming group's. */
EVR_HD static EVR__ALWAYS_INLINE int
evr__blas4(const evr_gpu_node4 *nodes, const evr_gpu_tri *tris, int root, const evr__tray *r,
           float tnear, float *tfar, int any, evr__stack_entry *stack, int sp0, evr__tri_hit *th,
           const evr__deform_src *ds, const evr__filter_src *fs)
{
    int node = root, sp = sp0, found = 0;
    for (;;) {
        int ci[4], lf[4], i, j;
        float ct[4];
        uint32_t lc[4], k;
        evr__node4(&nodes[node], r, tnear, *tfar, ci, ct, lf, lc);
        EVR__UNROLL
        for (i = 0; i < 4; i++) {
            for (k = 0; k < lc[i]; k++) {
                const uint32_t item = (uint32_t)lf[i] + k;
                float t, u, v;
                if (evr__leaf_tri(tris, ds, item, r, tnear, *tfar, &t, &u, &v) && t < *tfar &&
                    !evr__leaf_filtered(tris, ds, fs, item, u, v)) {
                    *tfar = t;
                    evr__leaf_hit(tris, ds, item, th);
                    th->u = u;
                    th->v = v;
                    found = 1;
                    if (any) return 1;
                }
            }
        }
        if (ct[0] < INFINITY && ct[0] <= *tfar) {
            node = ci[0];
            for (j = 3; j >= 1; j--) {
                if (ct[j] < INFINITY && ct[j] <= *tfar && sp < EVR_GPU_STACK_SIZE) {
                    stack[sp].a = (uint32_t)ci[j];
                    stack[sp].b = evr__f2u(ct[j]);
                    sp++;
                }
            }
            continue;
        }
        node = -1;
        while (sp > sp0) {
            sp--;
            if (evr__u2f(stack[sp].b) <= *tfar) {
                node = (int)stack[sp].a;
                break;
            }
        }
        if (node < 0) break;
    }
    return found;
}

/* ---- CW8 ---- */

EVR_HD static inline float evr__exp2_biased(uint8_t e) /* 2^(e - 127), e in 1..254 */
{
    return evr__u2f((uint32_t)e << 23);
}

/* Eight bytes of a node (8-byte aligned within it) as one word, byte i in bits 8i .. 8i + 7. */
EVR_HD static inline uint64_t evr__node_word(const uint8_t *bytes)
{
#ifdef __CUDA_ARCH__
    return __ldg((const unsigned long long *)bytes);
#else
    uint64_t w;
    memcpy(&w, bytes, sizeof w);
    return w;
#endif
}

/* Byte j (0..3) of a word as a float: 2^23 + q exactly, less 2^23 (cheaper than a conversion);
 * on the device one byte permutation (selector 0x7440 + j) builds 0x4b0000qq. */
EVR_HD static inline float evr__byte_float(uint32_t w, int j)
{
#ifdef __CUDA_ARCH__
    return __uint_as_float(__byte_perm(w, 0x4b000000u, 0x7440u + (uint32_t)j)) - 8388608.0f;
#else
    return evr__u2f(0x4b000000u | ((w >> (8 * j)) & 0xffu)) - 8388608.0f;
#endif
}

/* Hit mask of a CW8 node: bits 24 + (slot ^ oct_inv) for inner children, the item bits of leaf
 * children below 24. Each axis's near and far planes are chosen once for the node (by the sign of
 * the ray's direction) and its eight quantized bytes read as one word, taken four slots at a
 * time as 32-bit halves; a child's box is then p + q 2^e (one rounding: q 2^e is exact), as the
 * build checked it, and the slab test is evr__box's (evr__slab). */
EVR_HD static inline uint32_t evr__node8(const evr_gpu_node8 *n, const evr__tray *r, float tnear,
                                         float tfar)
{
    const float sx = evr__exp2_biased(n->e[0]), sy = evr__exp2_biased(n->e[1]),
                sz = evr__exp2_biased(n->e[2]);
    const float px = n->p[0], py = n->p[1], pz = n->p[2];
    const uint64_t meta = evr__node_word(n->meta);
    const uint64_t lx = evr__node_word(n->qlo[0]), ly = evr__node_word(n->qlo[1]),
                   lz = evr__node_word(n->qlo[2]);
    const uint64_t hx = evr__node_word(n->qhi[0]), hy = evr__node_word(n->qhi[1]),
                   hz = evr__node_word(n->qhi[2]);
    const uint64_t nx = r->ix >= 0.0f ? lx : hx, fx = r->ix >= 0.0f ? hx : lx;
    const uint64_t ny = r->iy >= 0.0f ? ly : hy, fy = r->iy >= 0.0f ? hy : ly;
    const uint64_t nz = r->iz >= 0.0f ? lz : hz, fz = r->iz >= 0.0f ? hz : lz;
    uint32_t hits = 0;
    int h, j;
    EVR__NO_UNROLL
    for (h = 0; h < 64; h += 32) {
        const uint32_t m4 = (uint32_t)(meta >> h), nx4 = (uint32_t)(nx >> h),
                       ny4 = (uint32_t)(ny >> h), nz4 = (uint32_t)(nz >> h),
                       fx4 = (uint32_t)(fx >> h), fy4 = (uint32_t)(fy >> h),
                       fz4 = (uint32_t)(fz >> h);
        EVR__NODE8_UNROLL
        for (j = 0; j < 4; j++) {
            const uint32_t m = (m4 >> (8 * j)) & 0xffu;
            uint32_t idx;
            if (!m) continue;
            float tn;
            if (!evr__slab(r, px + evr__byte_float(nx4, j) * sx, py + evr__byte_float(ny4, j) * sy,
                           pz + evr__byte_float(nz4, j) * sz, px + evr__byte_float(fx4, j) * sx,
                           py + evr__byte_float(fy4, j) * sy, pz + evr__byte_float(fz4, j) * sz,
                           tnear, tfar, &tn))
                continue;
            idx = m & 31u;
            if (idx >= 24u) idx = 24u + ((idx - 24u) ^ (uint32_t)r->oct_inv);
            hits |= (m >> 5) << idx;
        }
    }
    return hits;
}

/* Next node of a node group (base, hits with imask in the low byte): takes the highest hit bit
 * and pushes what remains. */
EVR_HD static inline uint32_t evr__group_next(uint32_t *base, uint32_t *hits, const evr__tray *r,
                                              evr__stack_entry *stack, int *sp)
{
    int bit = evr__msb(*hits);
    uint32_t imask, slot, index;
    *hits &= ~(1u << bit);
    imask = *hits & 0xffu;
    slot = (uint32_t)(bit - 24) ^ (uint32_t)r->oct_inv;
    index = *base + (uint32_t)evr__popc(imask & ((1u << slot) - 1u));
    if (*hits > 0x00ffffffu && *sp < EVR_GPU_STACK_SIZE) {
        stack[*sp].a = *base;
        stack[*sp].b = *hits;
        (*sp)++;
    }
    return index;
}

/* As evr__blas4, for CW8 nodes. */
EVR_HD static EVR__ALWAYS_INLINE int
evr__blas8(const evr_gpu_node8 *nodes, const evr_gpu_tri *tris, int root, const evr__tray *r,
           float tnear, float *tfar, int any, evr__stack_entry *stack, int sp0, evr__tri_hit *th,
           const evr__deform_src *ds, const evr__filter_src *fs)
{
    uint32_t ng_base = (uint32_t)root, ng_hits = 0x80000000u, tg_base = 0, tg_hits = 0;
    int sp = sp0, found = 0;
    for (;;) {
        if (ng_hits > 0x00ffffffu) {
            const evr_gpu_node8 *n = &nodes[evr__group_next(&ng_base, &ng_hits, r, stack, &sp)];
            uint32_t h = evr__node8(n, r, tnear, *tfar);
            EVR__STAT(nodes);
            ng_base = n->child_base;
            ng_hits = (h & 0xff000000u) | n->imask;
            tg_base = n->item_base;
            tg_hits = h & 0x00ffffffu;
        }
        while (tg_hits) {
            int bit = evr__msb(tg_hits);
            const uint32_t item = tg_base + (uint32_t)bit;
            float t, u, v;
            tg_hits &= ~(1u << bit);
            EVR__STAT(tris);
            if (evr__leaf_tri(tris, ds, item, r, tnear, *tfar, &t, &u, &v) && t < *tfar &&
                !evr__leaf_filtered(tris, ds, fs, item, u, v)) {
                *tfar = t;
                evr__leaf_hit(tris, ds, item, th);
                th->u = u;
                th->v = v;
                found = 1;
                if (any) return 1;
            }
        }
        if (ng_hits <= 0x00ffffffu) {
            if (sp == sp0) break;
            sp--;
            ng_base = stack[sp].a;
            ng_hits = stack[sp].b;
        }
    }
    return found;
}

/* ---- groups ---- */

/* A deforming group's tree (the general search only), out of line: inlined, its vertices'
 * interpolation doubled the general search's code and raised its register spills. */
EVR_HD static EVR__NOINLINE int
evr__blas_deform(const evr_gpu_scene_view *v, const evr_render_scene *rs, const evr_gpu_inst *in,
                 const evr__tray *r, float f, float tnear, float *tfar, int any,
                 evr__stack_entry *stack, int sp, evr__tri_hit *th, const evr__filter_src *fs)
{
    evr__deform_src ds;
    evr__filter_src fsrc;
    ds.tris = v->dtris;
    ds.view = rs->deforms[rs->instances[in->instance_base].deform];
    ds.fr = evr_key_interval(ds.view.num_keys, f, &ds.a);
    if (fs) {
        fsrc = *fs;
        fsrc.dbits = (uint32_t)rs->meshes[rs->instances[in->instance_base].mesh].filter & fsrc.bits;
        fs = &fsrc;
    }
    if (v->layout == EVR_GPU_LAYOUT_CW8)
        return evr__blas8(v->dnodes8, v->tris, -1 - in->root, r, tnear, tfar, any, stack, sp, th,
                          &ds, fs);
    return evr__blas4(v->dnodes4, v->tris, -1 - in->root, r, tnear, tfar, any, stack, sp, th, &ds,
                      fs);
}

/* Searches one group with the world ray (o, d) at time f; on a (nearer) hit shrinks *tfar
 * and fills hit (when not NULL). general (a constant where inlined): the general search: the
 * group may be a deforming one (root < 0: its tree in the deforming arrays, its vertices the
 * segment's keys at time f), and where the scene has meshes whose hits a material may rule out
 * (v->filtered), their hits are tested (core/hit_filter.h) and a ruled-out one is passed over:
 * the search goes on behind it, a shadow ray's too. layout: the trees' node layout, the top
 * level's, a constant where inlined (read from the view, it put both layouts' searches in
 * every top-level search). */
EVR_HD static EVR__ALWAYS_INLINE int
evr__instance(const evr_gpu_scene_view *v, const evr_render_scene *rs, const evr_gpu_inst *in,
              evr_v3 o, evr_v3 d, float f, float tnear, float *tfar, int any,
              evr__stack_entry *stack, int sp, evr_gpu_hit *hit, int general, int layout)
{
    evr_m34 inv;
    evr_v3 oo, od;
    evr__tray r;
    evr__tri_hit th;
    evr__filter_src fsrc;
    const evr__filter_src *fs = (const evr__filter_src *)0;
    int found;
    if (in->moving) {
        evr_m34 xf = evr_motion_eval(evr_rs_track(rs, in->track), f);
        inv = evr_m34_inverse(&xf);
    } else {
        inv = in->inv;
    }
    oo = evr_m34_point(&inv, o);
    od = evr_m34_vector(&inv, d);
    if (od.x == 0.0f && od.y == 0.0f && od.z == 0.0f) return 0; /* a zero scale: nothing there */
    evr__tray_init(&r, oo, od);
    th.prim = 0;
    th.inst = 0;
    th.u = th.v = 0.0f;
    if (general && v->filtered) {
        fsrc.rs = rs;
        fsrc.instance_base = in->instance_base;
        fsrc.dir = d;
        fsrc.f = f;
        fsrc.shadow = any;
        fsrc.bits = any ? EVR_FILTER_MASK : EVR_FILTER_MASK | EVR_FILTER_CULL;
        fsrc.dbits = 0;
        fs = &fsrc;
    }
    if (general && in->root < 0) {
        found = evr__blas_deform(v, rs, in, &r, f, tnear, tfar, any, stack, sp, &th, fs);
    } else if (layout == EVR_GPU_LAYOUT_CW8) {
        found = evr__blas8(v->nodes8, v->tris, in->root, &r, tnear, tfar, any, stack, sp, &th,
                           (const evr__deform_src *)0, fs);
    } else {
        found = evr__blas4(v->nodes4, v->tris, in->root, &r, tnear, tfar, any, stack, sp, &th,
                           (const evr__deform_src *)0, fs);
    }
    if (found && hit) {
        hit->t = *tfar;
        hit->u = th.u;
        hit->v = th.v;
        hit->prim = th.prim;
        hit->instance = in->instance_base + th.inst;
    }
    return found;
}

/* ---- top level ---- */

/* Which groups a search visits: all, all but the static group (world space, track -1), or it alone. */
#define EVR_GROUPS_ALL 0
#define EVR_GROUPS_MOVING 1
#define EVR_GROUPS_STATIC 2
EVR_HD static inline int evr__group_skipped(const evr_gpu_inst *in, int groups)
{
    return groups == EVR_GROUPS_MOVING   ? in->track < 0
           : groups == EVR_GROUPS_STATIC ? in->track >= 0
                                         : 0;
}

/* Top-level search; general (a constant where inlined): the general search (evr__instance). */
EVR_HD static EVR__ALWAYS_INLINE int evr__trace4(const evr_gpu_scene_view *v,
                                                 const evr_render_scene *rs, evr_ray ray,
                                                 float tnear, float tfar, float f, int any,
                                                 evr_gpu_hit *hit, int groups, int general)
{
    evr__stack_entry stack[EVR_GPU_STACK_SIZE];
    evr__tray r;
    int node = 0, sp = 0, found = 0;
    evr__tray_init(&r, ray.org, ray.dir);
    for (;;) {
        int ci[4], lf[4], i, j;
        float ct[4];
        uint32_t lc[4], k;
        evr__node4(&v->top4[node], &r, tnear, tfar, ci, ct, lf, lc);
        for (i = 0; i < 4; i++) {
            for (k = 0; k < lc[i]; k++) {
                if (evr__group_skipped(&v->insts[(uint32_t)lf[i] + k], groups)) continue;
                if (evr__instance(v, rs, &v->insts[(uint32_t)lf[i] + k], ray.org, ray.dir, f, tnear,
                                  &tfar, any, stack, sp, hit, general, EVR_GPU_LAYOUT_BVH4)) {
                    found = 1;
                    if (any) return 1;
                }
            }
        }
        if (ct[0] < INFINITY && ct[0] <= tfar) {
            node = ci[0];
            for (j = 3; j >= 1; j--) {
                if (ct[j] < INFINITY && ct[j] <= tfar && sp < EVR_GPU_STACK_SIZE) {
                    stack[sp].a = (uint32_t)ci[j];
                    stack[sp].b = evr__f2u(ct[j]);
                    sp++;
                }
            }
            continue;
        }
        node = -1;
        while (sp > 0) {
            sp--;
            if (evr__u2f(stack[sp].b) <= tfar) {
                node = (int)stack[sp].a;
                break;
            }
        }
        if (node < 0) break;
    }
    return found;
}

EVR_HD static EVR__ALWAYS_INLINE int evr__trace8(const evr_gpu_scene_view *v,
                                                 const evr_render_scene *rs, evr_ray ray,
                                                 float tnear, float tfar, float f, int any,
                                                 evr_gpu_hit *hit, int groups, int general)
{
    evr__stack_entry stack[EVR_GPU_STACK_SIZE];
    evr__tray r;
    uint32_t ng_base = 0, ng_hits = 0x80000000u, tg_base = 0, tg_hits = 0;
    int sp = 0, found = 0;
    evr__tray_init(&r, ray.org, ray.dir);
    for (;;) {
        if (ng_hits > 0x00ffffffu) {
            const evr_gpu_node8 *n = &v->top8[evr__group_next(&ng_base, &ng_hits, &r, stack, &sp)];
            uint32_t h = evr__node8(n, &r, tnear, tfar);
            EVR__STAT(top_nodes);
            ng_base = n->child_base;
            ng_hits = (h & 0xff000000u) | n->imask;
            tg_base = n->item_base;
            tg_hits = h & 0x00ffffffu;
        }
        while (tg_hits) {
            int bit = evr__msb(tg_hits);
            tg_hits &= ~(1u << bit);
            if (evr__group_skipped(&v->insts[tg_base + (uint32_t)bit], groups)) continue;
            EVR__STAT(groups);
            if (evr__instance(v, rs, &v->insts[tg_base + (uint32_t)bit], ray.org, ray.dir, f, tnear,
                              &tfar, any, stack, sp, hit, general, EVR_GPU_LAYOUT_CW8)) {
                found = 1;
                if (any) return 1;
            }
        }
        if (ng_hits <= 0x00ffffffu) {
            if (sp == 0) break;
            sp--;
            ng_base = stack[sp].a;
            ng_hits = stack[sp].b;
        }
    }
    return found;
}

/* Nearest (any != 0: first) hit among some groups (EVR_GROUPS_*) in (tnear, tfar] at time f, in
 * node layout `layout`; general: the scene has deforming groups or filtered meshes
 * (evr__trace_general; the CUDA kernels' gpu_trace makes the same choice with its template's
 * constants). */
EVR_HD static EVR__ALWAYS_INLINE int
evr__trace(const evr_gpu_scene_view *v, const evr_render_scene *rs, evr_ray ray, float tnear,
           float tfar, float f, int any, evr_gpu_hit *hit, int groups, int layout, int general)
{
    if (v->num_top_nodes == 0) return 0;
    if (layout == EVR_GPU_LAYOUT_CW8)
        return evr__trace8(v, rs, ray, tnear, tfar, f, any, hit, groups, general);
    return evr__trace4(v, rs, ray, tnear, tfar, f, any, hit, groups, general);
}

/* Whether the scene needs the general search (EVR_GPU_TRACE_GENERAL). */
EVR_HD static inline int evr__trace_general(const evr_gpu_scene_view *v)
{
    return v->num_dtris != 0 || v->filtered;
}

/* The nearest hit among some groups only (EVR_GROUPS_*), nearer than tmax (ties go to tmax).
 * The nearest hit of all groups is the static group's unless the others have one nearer (what
 * a camera ray's static hit, kept per pixel while the camera holds still, saves). */
EVR_HD static inline int evr_trace_closest_groups(const evr_gpu_scene_view *v,
                                                  const evr_render_scene *rs, evr_ray ray,
                                                  float tmax, float f, int groups, evr_gpu_hit *hit)
{
    return evr__trace(v, rs, ray, 0.0f, tmax, f, 0, hit, groups, v->layout, evr__trace_general(v));
}

/* Nearest hit along the world ray in (0, tmax] at normalized segment time f in [0, 1]. */
EVR_HD static inline int evr_trace_closest(const evr_gpu_scene_view *v, const evr_render_scene *rs,
                                           evr_ray ray, float tmax, float f, evr_gpu_hit *hit)
{
    return evr_trace_closest_groups(v, rs, ray, tmax, f, EVR_GROUPS_ALL, hit);
}

/* Whether anything lies along the world ray in (tnear, tfar] at time f (stops at the first hit). */
EVR_HD static inline int evr_trace_any(const evr_gpu_scene_view *v, const evr_render_scene *rs,
                                       evr_ray ray, float tnear, float tfar, float f)
{
    return evr__trace(v, rs, ray, tnear, tfar, f, 1, 0, EVR_GROUPS_ALL, v->layout,
                      evr__trace_general(v));
}

#endif
