// The CUDA execution space: for_each, reduce and the stable key sort for Device.
// Included only by cuda/*.cu, before the drivers they instantiate. No physics here.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <vector>

#include "core/exec.hpp"
#include "cuda/device_buffer.hpp"

namespace sphdem {

namespace detail {
void check_cuda(cudaError_t e, const char* what);

// Blocks of 256 threads. SPHDEM_CUDA_MIN_BLOCKS (a build option) asks ptxas for at least that many
// resident blocks per multiprocessor, capping the registers of the neighbour loops.
#ifndef SPHDEM_CUDA_MIN_BLOCKS
#define SPHDEM_CUDA_MIN_BLOCKS 1
#endif
constexpr int kForEachBlock = 256;

template <class F>
__global__ void __launch_bounds__(kForEachBlock, SPHDEM_CUDA_MIN_BLOCKS)
    for_each_kernel(Index n, F f) {
  const Index i = Index(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(i);
}

// Each block reduces a fixed chunk of the range in a fixed tree order: deterministic.
template <class Op, class T, class F>
__global__ void reduce_kernel(Index n, Index chunk, F f, T* partial) {
  __shared__ T s[256];
  const Index lo = Index(blockIdx.x) * chunk;
  const Index hi = lo + chunk < n ? lo + chunk : n;
  T acc = Op::template identity<T>();
  for (Index i = lo + threadIdx.x; i < hi; i += blockDim.x) acc = Op::combine(acc, T(f(i)));
  s[threadIdx.x] = acc;
  __syncthreads();
  for (unsigned w = blockDim.x / 2; w > 0; w /= 2) {
    if (threadIdx.x < w) s[threadIdx.x] = Op::combine(s[threadIdx.x], s[threadIdx.x + w]);
    __syncthreads();
  }
  if (threadIdx.x == 0) partial[blockIdx.x] = s[0];
}
}  // namespace detail

template <class F>
void for_each(Device, Index n, const F& f) {
  if (n <= 0) return;
  constexpr int kBlock = detail::kForEachBlock;
  const Index blocks = (n + kBlock - 1) / kBlock;
  detail::for_each_kernel<<<unsigned(blocks), kBlock>>>(n, f);
  detail::check_cuda(cudaGetLastError(), "for_each launch");
}

// One thread per iteration already balances uneven work on the device.
template <class F>
void for_each_uneven(Device d, Index n, const F& f) {
  for_each(d, n, f);
}

template <class Op, class T, class F>
T reduce(Device, Index n, const F& f) {
  const Index chunk = (n + kReduceChunks - 1) / kReduceChunks;
  Buffer<T, Device> partial(kReduceChunks);
  if (n > 0) {
    detail::reduce_kernel<Op, T><<<unsigned(kReduceChunks), 256>>>(n, chunk, f, partial.data());
    detail::check_cuda(cudaGetLastError(), "reduce launch");
  } else {
    return Op::template identity<T>();
  }
  std::vector<T> h;
  partial.download(h);
  T acc = Op::template identity<T>();
  for (const T& v : h) acc = Op::combine(acc, v);
  return acc;
}

// Waits for the kernels queued so far, so that a host clock brackets their run (phase timers).
inline void fence(Device) {
  detail::check_cuda(cudaDeviceSynchronize(), "fence");
}

// Phase timing on the device (core/exec.hpp): each mark records a CUDA event on the default
// stream, the one every kernel and copy here uses, so the time between two marks is the device's
// timeline between them, host work in the phase (halo staging) included. settle() waits for the
// step's last event and reads the elapsed times; the events are then reused.
template <>
class PhaseClock<Device> {
 public:
  using Mark = int;
  PhaseClock() = default;
  PhaseClock(const PhaseClock&) = delete;
  PhaseClock& operator=(const PhaseClock&) = delete;
  ~PhaseClock() {
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
  }
  Mark mark() {
    if (used_ == events_.size()) {
      cudaEvent_t e;
      detail::check_cuda(cudaEventCreate(&e), "cudaEventCreate (phase clock)");
      events_.push_back(e);
    }
    detail::check_cuda(cudaEventRecord(events_[used_], 0), "cudaEventRecord (phase clock)");
    return Mark(used_++);
  }
  void add(double& acc, Mark a, Mark b) { pending_.push_back(Pending{&acc, a, b}); }
  void settle() {
    if (!pending_.empty()) {
      detail::check_cuda(cudaEventSynchronize(events_[used_ - 1]), "cudaEventSynchronize");
      for (const Pending& p : pending_) {
        float ms = 0;
        detail::check_cuda(
            cudaEventElapsedTime(&ms, events_[std::size_t(p.a)], events_[std::size_t(p.b)]),
            "cudaEventElapsedTime");
        *p.acc += double(ms) * 1e-3;
      }
      pending_.clear();
    }
    used_ = 0;
  }

 private:
  struct Pending {
    double* acc;
    Mark a, b;
  };
  std::vector<cudaEvent_t> events_;
  std::vector<Pending> pending_;
  std::size_t used_ = 0;
};

void sort_pairs_stable(Device, std::uint64_t* keys, std::uint32_t* values, Index n,
                       std::uint64_t max_key);

}  // namespace sphdem
