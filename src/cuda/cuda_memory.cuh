/* Device and pinned host memory of the CUDA backend: buffers that grow (dbuf in device memory,
 * hbuf in pinned host memory) and their size for the run's statistics. */
#ifndef EVR_CUDA_CUDA_MEMORY_CUH
#define EVR_CUDA_CUDA_MEMORY_CUH

#include <cuda_runtime.h>
#include <stddef.h>
#include <stdint.h>

/* A buffer that grows (contents not kept), in device memory or in pinned host memory. */
struct device_memory {
    static cudaError_t alloc(void **p, size_t n) { return cudaMalloc(p, n); }
    static void release(void *p) { cudaFree(p); }
};
struct pinned_memory {
    static cudaError_t alloc(void **p, size_t n) { return cudaMallocHost(p, n); }
    static void release(void *p) { cudaFreeHost(p); }
};

template <typename T, typename M> struct growing_buffer {
    T *p = nullptr;
    size_t cap = 0;
    cudaError_t reserve(size_t n, bool exact = false)
    {
        if (n <= cap) return cudaSuccess;
        size_t c = cap ? cap : 1;
        while (c < n) c *= 2;
        if (exact) c = n;
        release();
        void *q = nullptr;
        cudaError_t e = M::alloc(&q, c * sizeof(T));
        if (e == cudaSuccess) {
            p = (T *)q;
            cap = c;
        }
        return e;
    }
    void release()
    {
        if (p) M::release(p);
        p = nullptr;
        cap = 0;
    }
};
template <typename T> using dbuf = growing_buffer<T, device_memory>;
template <typename T> using hbuf = growing_buffer<T, pinned_memory>;

/* Bytes of device memory a buffer holds. */
template <typename T> static uint64_t bytes(const dbuf<T> &d)
{
    return (uint64_t)d.cap * sizeof(T);
}

#endif
