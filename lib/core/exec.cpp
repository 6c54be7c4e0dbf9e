#include "core/exec.hpp"

#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace sphdem {

int host_thread_count() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

void sort_pairs_stable(Host, std::uint64_t* keys, std::uint32_t* values, Index n,
                       std::uint64_t max_key) {
  if (n <= 1) return;
  int bits = 0;
  while (bits < 64 && (max_key >> bits) != 0) ++bits;
  std::vector<std::uint64_t> k2(n);
  std::vector<std::uint32_t> v2(n);
  std::uint64_t* ks = keys;
  std::uint32_t* vs = values;
  std::uint64_t* kd = k2.data();
  std::uint32_t* vd = v2.data();
  for (int shift = 0; shift < bits; shift += 8) {
    Index count[257] = {0};
    for (Index i = 0; i < n; ++i) ++count[((ks[i] >> shift) & 0xff) + 1];
    for (int d = 0; d < 256; ++d) count[d + 1] += count[d];
    for (Index i = 0; i < n; ++i) {
      const Index dst = count[(ks[i] >> shift) & 0xff]++;
      kd[dst] = ks[i];
      vd[dst] = vs[i];
    }
    std::swap(ks, kd);
    std::swap(vs, vd);
  }
  if (ks != keys) {
    std::copy(ks, ks + n, keys);
    std::copy(vs, vs + n, values);
  }
}

}  // namespace sphdem
