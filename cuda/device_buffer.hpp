// Buffer<T, Device>: device memory owned by the host object. Plain C++ (no CUDA headers), so
// host code can hold device buffers and copy them; only kernels touch their contents.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "core/exec.hpp"
#include "cuda/device.hpp"

namespace sphdem {

template <class T>
class Buffer<T, Device> {
 public:
  Buffer() = default;
  explicit Buffer(std::size_t n) { resize(n); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& o) noexcept { swap(o); }
  Buffer& operator=(Buffer&& o) noexcept {
    swap(o);
    return *this;
  }
  ~Buffer() { cuda::device_free(p_); }

  // Keeps the first min(n, size()) elements.
  void resize(std::size_t n) {
    if (n <= cap_) {
      n_ = n;
      return;
    }
    T* q = static_cast<T*>(cuda::device_alloc(n * sizeof(T)));
    if (n_ > 0) cuda::copy_device_to_device(q, p_, n_ * sizeof(T));
    cuda::device_free(p_);
    p_ = q;
    n_ = cap_ = n;
  }
  std::size_t size() const { return n_; }
  T* data() { return p_; }
  const T* data() const { return p_; }
  void swap(Buffer& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    std::swap(cap_, o.cap_);
  }

  void upload(const std::vector<T>& h) {
    resize(h.size());
    if (!h.empty()) cuda::copy_to_device(p_, h.data(), h.size() * sizeof(T));
  }
  void download(std::vector<T>& h) const {
    h.resize(n_);
    if (n_ > 0) cuda::copy_to_host(h.data(), p_, n_ * sizeof(T));
  }
  // n values from slot b into host memory.
  void download_range(T* out, std::size_t b, std::size_t n) const {
    if (n > 0) cuda::copy_to_host(out, p_ + b, n * sizeof(T));
  }
  // n values from host memory into slots [b, b + n).
  void upload_range(const T* in, std::size_t b, std::size_t n) {
    if (n > 0) cuda::copy_to_device(p_ + b, in, n * sizeof(T));
  }

 private:
  T* p_ = nullptr;
  std::size_t n_ = 0, cap_ = 0;
};

// HostStage (core/exec.hpp) for device buffers: a pinned host array, grown as needed and kept.
template <class T>
class HostStage<T, Device> {
 public:
  HostStage() = default;
  HostStage(const HostStage&) = delete;
  HostStage& operator=(const HostStage&) = delete;
  ~HostStage() { cuda::pinned_free(p_); }

  T* read(Buffer<T, Device>& b, Index n) {
    reserve(n);
    if (n > 0) cuda::copy_to_host(p_, b.data(), std::size_t(n) * sizeof(T));
    return p_;
  }
  T* space(Buffer<T, Device>& b, Index n) {
    b.resize(std::size_t(n > 0 ? n : 1));
    reserve(n);
    return p_;
  }
  void write(Buffer<T, Device>& b, Index n) {
    if (n > 0) cuda::copy_to_device(b.data(), p_, std::size_t(n) * sizeof(T));
  }

 private:
  void reserve(Index n) {
    const std::size_t want = std::size_t(n > 0 ? n : 1);
    if (want <= cap_) return;
    cuda::pinned_free(p_);
    p_ = nullptr;
    p_ = static_cast<T*>(cuda::pinned_alloc(want * sizeof(T)));
    cap_ = want;
  }
  T* p_ = nullptr;
  std::size_t cap_ = 0;
};

}  // namespace sphdem
