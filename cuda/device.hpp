// Plain C++ view of the CUDA execution space: what the host code may call without nvcc.
// Implemented in cuda/*.cu when SPHDEM_ENABLE_CUDA is ON, and in cuda/no_cuda.cpp otherwise.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace sphdem::cuda {

struct GpuInfo {
  int index = 0;
  std::string name;
  std::size_t memory_bytes = 0;
  int cc_major = 0, cc_minor = 0;
  double bandwidth_gbs = 0;  // theoretical peak from clock and bus width
};

bool compiled_with_cuda();
// GPUs the runtime sees. Empty without a GPU or driver; `why` then says what the runtime said.
std::vector<GpuInfo> list_gpus(std::string* why = nullptr);
// Selects the GPU for this process (node-local rank modulo the device count).
void select_device(int index);
// The selected GPU's index (-1 without CUDA or GPU).
int current_device();

// Raw device memory, used by Buffer<T, Device>.
void* device_alloc(std::size_t bytes);
void device_free(void* p) noexcept;
// Returns the blocks the device allocator keeps for reuse to the driver.
void release_cached_memory();
void copy_to_device(void* dst, const void* src, std::size_t bytes);
void copy_to_host(void* dst, const void* src, std::size_t bytes);
void copy_device_to_device(void* dst, const void* src, std::size_t bytes);
// Page-locked host memory (cudaMallocHost), for staging MPI traffic: Debian's Open MPI is not
// CUDA-aware, so halo fields go device -> pinned host -> MPI -> pinned host -> device.
void* pinned_alloc(std::size_t bytes);
void pinned_free(void* p) noexcept;
void synchronize();

}  // namespace sphdem::cuda
