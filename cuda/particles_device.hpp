// Moving a particle set between the host and the device, field by field.
#pragma once

#include <vector>

#include "cuda/device_buffer.hpp"
#include "solver/particles.hpp"

namespace sphdem {

inline void to_space(Device, ParticleSet<Host>&& src, ParticleSet<Device>& dst) {
  dst.n_fluid = src.n_fluid;
  dst.n_halo = src.n_halo;
  dst.n_wall = src.n_wall;
  dst.n_grain = src.n_grain;
  // Visit the host fields and the device fields in the same fixed order.
  std::vector<void*> hosts;
  src.for_each_field([&](const char*, auto& b) { hosts.push_back(&b); });
  std::size_t k = 0;
  dst.for_each_field([&](const char*, auto& b) {
    using T = std::remove_pointer_t<decltype(b.data())>;
    auto* h = static_cast<Buffer<T, Host>*>(hosts[k++]);
    b.upload(h->vec());
  });
}

inline void to_host(Device, ParticleSet<Device>& src, ParticleSet<Host>& dst) {
  dst.n_fluid = src.n_fluid;
  dst.n_halo = src.n_halo;
  dst.n_wall = src.n_wall;
  dst.n_grain = src.n_grain;
  std::vector<void*> hosts;
  dst.for_each_field([&](const char*, auto& b) { hosts.push_back(&b); });
  std::size_t k = 0;
  src.for_each_field([&](const char*, auto& b) {
    using T = std::remove_pointer_t<decltype(b.data())>;
    auto* h = static_cast<Buffer<T, Host>*>(hosts[k++]);
    b.download(h->vec());
    h->resize(std::size_t(src.size()));
  });
}

}  // namespace sphdem
