// SPHDEM_HD marks functions compiled for both the host and the device.
// Physics lives in SPHDEM_HD inline functions of plain values; the CPU backend calls them from an
// OpenMP loop and the CUDA backend from a kernel. See DESIGN.md §3.
#pragma once

#if defined(__CUDACC__)
#define SPHDEM_HD __host__ __device__
#define SPHDEM_LAMBDA [=] __host__ __device__
#else
#define SPHDEM_HD
#define SPHDEM_LAMBDA [=]
#endif

// SPHDEM_INLINE forces inlining of a per-pair function into its neighbour loop (g++ otherwise
// keeps the pair physics out of line once the loop body grows, at about 40% of the pass's time).
#if defined(__CUDACC__)
#define SPHDEM_INLINE __forceinline__
#elif defined(__GNUC__)
#define SPHDEM_INLINE inline __attribute__((always_inline))
#else
#define SPHDEM_INLINE inline
#endif

// SPHDEM_FLATTEN inlines every call inside a neighbour loop, the caller's pair lambda included
// (g++ keeps a large lambda out of line and reloads its captures through memory at each pair).
// nvcc inlines device lambdas on its own.
#if !defined(__CUDACC__) && defined(__GNUC__) && !defined(__clang__)
#define SPHDEM_FLATTEN __attribute__((flatten))
#else
#define SPHDEM_FLATTEN
#endif
