// Execution spaces (DESIGN.md §3). A driver is written once, templated on the space:
//
//   template <class Space> void compute_x(Space s, View v) {
//     for_each(s, v.n, SPHDEM_LAMBDA(Index i) { v.x[i] = physics_function(...); });
//   }
//
// Host runs the functor in an OpenMP loop. Device (declared here, implemented in cuda/) launches
// the same functor in a CUDA kernel. Overloads are found by argument-dependent lookup at
// instantiation, so cuda/*.cu files include cuda/exec_device.cuh before instantiating a driver.
//
// Reductions are deterministic: the range is cut into a fixed number of chunks whatever the
// thread count, each chunk is summed in index order, and the chunk results are combined in order.
// Two runs give bit-identical sums.
#pragma once

#include <algorithm>
#include <cstddef>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

struct Host {
  static constexpr const char* name = "host";
};
struct Device {
  static constexpr const char* name = "device";
};

// ---------------------------------------------------------------------------------------------
// Reduction operators (usable on both sides).
struct SumOp {
  template <class T>
  SPHDEM_HD static T identity() {
    return T(0);
  }
  template <class T>
  SPHDEM_HD static T combine(T a, T b) {
    return a + b;
  }
};
struct MinOp {
  template <class T>
  SPHDEM_HD static T identity() {
    return std::numeric_limits<T>::max();
  }
  template <class T>
  SPHDEM_HD static T combine(T a, T b) {
    return b < a ? b : a;
  }
};
struct MaxOp {
  template <class T>
  SPHDEM_HD static T identity() {
    return std::numeric_limits<T>::lowest();
  }
  template <class T>
  SPHDEM_HD static T combine(T a, T b) {
    return a < b ? b : a;
  }
};

// ---------------------------------------------------------------------------------------------
// Host space.
int host_thread_count();

template <class F>
void for_each(Host, Index n, const F& f) {
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) f(i);
}

// for_each for loops whose iterations differ widely in cost: a boundary slot beside fluid sums
// over a hundred neighbours, one in a dry part of the channel over none, and the busy slots lie
// together in cell order, so a static split hands them all to one thread. Threads take chunks as
// they finish. Each iteration writes only its own outputs, so results do not depend on the
// schedule.
constexpr Index kUnevenChunk = 256;
template <class F>
void for_each_uneven(Host, Index n, const F& f) {
#pragma omp parallel for schedule(dynamic, kUnevenChunk)
  for (Index i = 0; i < n; ++i) f(i);
}

// Phase timing (`sphdem bench`): mark() at each phase boundary, add(acc, a, b) adds the seconds
// from mark a to mark b to `acc`, settle() makes every added time final (once per step). The
// host reads a steady clock, final at once; the device records CUDA events (cuda/exec_device.cuh).
template <class Space>
class PhaseClock;

template <>
class PhaseClock<Host> {
 public:
  using Mark = std::chrono::steady_clock::time_point;
  Mark mark() const { return std::chrono::steady_clock::now(); }
  void add(double& acc, Mark a, Mark b) const {
    acc += std::chrono::duration<double>(b - a).count();
  }
  void settle() const {}
};

// Waits until the space's queued work is done; phase timers read the clock after it (Host: no-op).
inline void fence(Host) {}

// Number of chunks of a deterministic reduction; fixed so results do not depend on threads.
constexpr Index kReduceChunks = 256;

template <class Op, class T, class F>
T reduce(Host, Index n, const F& f) {
  T partial[kReduceChunks];
  const Index chunk = (n + kReduceChunks - 1) / kReduceChunks;
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < kReduceChunks; ++c) {
    T acc = Op::template identity<T>();
    const Index lo = c * chunk, hi = std::min(n, lo + chunk);
    for (Index i = lo; i < hi; ++i) acc = Op::combine(acc, T(f(i)));
    partial[c] = acc;
  }
  T acc = Op::template identity<T>();
  for (Index c = 0; c < kReduceChunks; ++c) acc = Op::combine(acc, partial[c]);
  return acc;
}

// ---------------------------------------------------------------------------------------------
// Buffers typed by space. Buffer<T, Host> is a plain vector; Buffer<T, Device> (cuda/) owns
// device memory. Drivers only see raw pointers through data().
template <class T, class Space>
class Buffer;

template <class T>
class Buffer<T, Host> {
 public:
  Buffer() = default;
  explicit Buffer(std::size_t n) : v_(n) {}
  void resize(std::size_t n) { v_.resize(n); }
  std::size_t size() const { return v_.size(); }
  T* data() { return v_.data(); }
  const T* data() const { return v_.data(); }
  T& operator[](std::size_t i) { return v_[i]; }
  const T& operator[](std::size_t i) const { return v_[i]; }
  std::vector<T>& vec() { return v_; }
  const std::vector<T>& vec() const { return v_; }
  void swap(Buffer& o) noexcept { v_.swap(o.v_); }
  // n values from slot b into host memory (as Buffer<T, Device>::download_range).
  void download_range(T* out, std::size_t b, std::size_t n) const {
    std::copy(v_.begin() + std::ptrdiff_t(b), v_.begin() + std::ptrdiff_t(b + n), out);
  }
  void upload_range(const T* in, std::size_t b, std::size_t n) {
    std::copy(in, in + n, v_.begin() + std::ptrdiff_t(b));
  }

 private:
  std::vector<T> v_;
};

// Host memory that MPI reads and writes for the values of a Buffer<T, Space> (DESIGN.md §5: Open
// MPI here is not CUDA-aware). On the host it is the buffer's own storage; the device version
// (cuda/device_buffer.hpp) copies through a pinned host array it keeps between calls.
template <class T, class Space>
class HostStage;

template <class T>
class HostStage<T, Host> {
 public:
  // The first n values of b, readable on the host.
  T* read(Buffer<T, Host>& b, Index) { return b.data(); }
  // Host memory for n values that write() then puts into b (sized at least 1).
  T* space(Buffer<T, Host>& b, Index n) {
    b.resize(std::size_t(n > 0 ? n : 1));
    return b.data();
  }
  void write(Buffer<T, Host>&, Index) {}
};

// ---------------------------------------------------------------------------------------------
// Stable sort of (key, value) pairs by key. Values are usually the identity permutation, and on
// return they hold the source index of each sorted slot. Host: LSD radix sort on 8-bit digits of
// the bits that are used (max_key). Device: CUB radix sort (cuda/sort.cu).
void sort_pairs_stable(Host, std::uint64_t* keys, std::uint32_t* values, Index n,
                       std::uint64_t max_key);

}  // namespace sphdem
