// CUDA runtime wrappers: device discovery, memory, copies, and the CUB radix sort.
#include <cub/device/device_radix_sort.cuh>

#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>
#include <unordered_map>

#include "core/error.hpp"
#include "cuda/device.hpp"
#include "cuda/exec_device.cuh"

namespace sphdem {
namespace detail {
void check_cuda(cudaError_t e, const char* what) {
  if (e != cudaSuccess) {
    std::ostringstream os;
    os << "CUDA error in " << what << ": " << cudaGetErrorString(e);
    throw RuntimeFault(os.str());
  }
}
}  // namespace detail

namespace cuda {
using detail::check_cuda;

bool compiled_with_cuda() {
  return true;
}

std::vector<GpuInfo> list_gpus(std::string* why) {
  std::vector<GpuInfo> out;
  int n = 0;
  const cudaError_t e = cudaGetDeviceCount(&n);
  if (e != cudaSuccess) {
    if (why) *why = cudaGetErrorString(e);
    cudaGetLastError();  // clear the sticky error
    return out;
  }
  for (int i = 0; i < n; ++i) {
    cudaDeviceProp p{};
    if (cudaGetDeviceProperties(&p, i) != cudaSuccess) continue;
    GpuInfo g;
    g.index = i;
    g.name = p.name;
    g.memory_bytes = p.totalGlobalMem;
    g.cc_major = p.major;
    g.cc_minor = p.minor;
    int mem_clock_khz = 0, bus_bits = 0;
    cudaDeviceGetAttribute(&mem_clock_khz, cudaDevAttrMemoryClockRate, i);
    cudaDeviceGetAttribute(&bus_bits, cudaDevAttrGlobalMemoryBusWidth, i);
    g.bandwidth_gbs = 2.0 * mem_clock_khz * 1e3 * (bus_bits / 8.0) / 1e9;
    out.push_back(g);
  }
  if (n == 0 && why) *why = "no CUDA device";
  return out;
}

void select_device(int index) {
  check_cuda(cudaSetDevice(index), "cudaSetDevice");
}

int current_device() {
  int d = -1;
  if (cudaGetDevice(&d) != cudaSuccess) {
    cudaGetLastError();
    return -1;
  }
  return d;
}

// Device memory goes through a small caching pool: the solver's per-step scratch (sort buffers,
// permutation scratch, reduction partials) would otherwise cost a cudaMalloc and a synchronising
// cudaFree every step, which measured 3-4 ms of a 1 M particle step on an H200. A freed block is
// kept and handed out again for a request of the same size class (up to 2x larger). When
// cudaMalloc fails, the cached blocks are released and the allocation is retried once.
// SPHDEM_DEVICE_POOL=0 turns the pool off (compute-sanitizer then sees every free); any value but 0
// or 1 is refused.
namespace {
struct Pool {
  std::mutex m;
  std::multimap<std::size_t, void*> free_blocks;   // size -> block
  std::unordered_map<void*, std::size_t> size_of;  // live and cached blocks
  bool enabled = true;
  Pool() {
    const char* e = std::getenv("SPHDEM_DEVICE_POOL");
    if (!e) return;
    const std::string v(e);
    if (v != "0" && v != "1")
      throw InputError("environment: SPHDEM_DEVICE_POOL=" + v +
                       ": expected 0 (device memory pool off) or 1 (on, the default)");
    enabled = v == "1";
  }
  void release_locked() {
    for (auto& [sz, p] : free_blocks) {
      cudaFree(p);
      size_of.erase(p);
    }
    free_blocks.clear();
  }
};
Pool& pool() {
  static Pool* p = new Pool();  // never destroyed: frees may arrive during static teardown
  return *p;
}
}  // namespace

void* device_alloc(std::size_t bytes) {
  if (bytes == 0) return nullptr;
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.m);
  if (pl.enabled) {
    auto it = pl.free_blocks.lower_bound(bytes);
    if (it != pl.free_blocks.end() && it->first <= 2 * bytes) {
      void* p = it->second;
      pl.free_blocks.erase(it);
      return p;
    }
  }
  void* p = nullptr;
  cudaError_t e = cudaMalloc(&p, bytes);
  if (e == cudaErrorMemoryAllocation && !pl.free_blocks.empty()) {
    cudaGetLastError();
    pl.release_locked();
    e = cudaMalloc(&p, bytes);
  }
  check_cuda(e, "cudaMalloc");
  if (pl.enabled) pl.size_of[p] = bytes;
  return p;
}
void device_free(void* p) noexcept {
  if (!p) return;
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.m);
  const auto it = pl.size_of.find(p);
  if (!pl.enabled || it == pl.size_of.end()) {
    cudaFree(p);
    return;
  }
  pl.free_blocks.emplace(it->second, p);
}
void release_cached_memory() {
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.m);
  pl.release_locked();
}
void copy_to_device(void* dst, const void* src, std::size_t bytes) {
  check_cuda(cudaMemcpy(dst, src, bytes, cudaMemcpyHostToDevice), "copy to device");
}
void copy_to_host(void* dst, const void* src, std::size_t bytes) {
  check_cuda(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToHost), "copy to host");
}
void copy_device_to_device(void* dst, const void* src, std::size_t bytes) {
  check_cuda(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToDevice), "copy on device");
}
void synchronize() {
  check_cuda(cudaDeviceSynchronize(), "synchronize");
}
void* pinned_alloc(std::size_t bytes) {
  if (bytes == 0) return nullptr;
  void* p = nullptr;
  check_cuda(cudaMallocHost(&p, bytes), "cudaMallocHost");
  return p;
}
void pinned_free(void* p) noexcept {
  if (p) cudaFreeHost(p);
}
}  // namespace cuda

void sort_pairs_stable(Device, std::uint64_t* keys, std::uint32_t* values, Index n,
                       std::uint64_t max_key) {
  if (n <= 1) return;
  int bits = 0;
  while (bits < 64 && (max_key >> bits) != 0) ++bits;
  if (bits == 0) bits = 1;
  Buffer<std::uint64_t, Device> k2{std::size_t(n)};
  Buffer<std::uint32_t, Device> v2{std::size_t(n)};
  cub::DoubleBuffer<std::uint64_t> kb(keys, k2.data());
  cub::DoubleBuffer<std::uint32_t> vb(values, v2.data());
  std::size_t temp_bytes = 0;
  detail::check_cuda(cub::DeviceRadixSort::SortPairs(nullptr, temp_bytes, kb, vb, int(n), 0, bits),
                     "radix sort size");
  Buffer<unsigned char, Device> temp(temp_bytes);
  detail::check_cuda(
      cub::DeviceRadixSort::SortPairs(temp.data(), temp_bytes, kb, vb, int(n), 0, bits),
      "radix sort");
  if (kb.Current() != keys) {
    cuda::copy_device_to_device(keys, kb.Current(), std::size_t(n) * sizeof(std::uint64_t));
    cuda::copy_device_to_device(values, vb.Current(), std::size_t(n) * sizeof(std::uint32_t));
  }
}

}  // namespace sphdem
