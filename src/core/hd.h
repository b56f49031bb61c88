/* EVR_HD marks code shared by the C compiler and nvcc: host and device. */
#ifndef EVR_CORE_HD_H
#define EVR_CORE_HD_H

#ifdef __CUDACC__
#define EVR_HD __host__ __device__
#else
#define EVR_HD
#endif

#endif
