// CUDA runtime wrappers: device discovery, memory, copies, and the CUB radix sort.
#include <cub/device/device_radix_sort.cuh>

#include <sstream>

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

void* device_alloc(std::size_t bytes) {
  void* p = nullptr;
  if (bytes == 0) return nullptr;
  check_cuda(cudaMalloc(&p, bytes), "cudaMalloc");
  return p;
}
void device_free(void* p) noexcept {
  if (p) cudaFree(p);
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
