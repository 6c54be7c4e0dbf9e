// Wendland C2 kernel, seed Eq. (2): W(q,h) = alpha_D (1 - q/2)^4 (1 + 2q) for 0 <= q <= 2,
// q = r/h; alpha_D = 7/(4 pi h^2) in 2D and 21/(16 pi h^3) in 3D. Support radius 2h.
#pragma once

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

struct KernelParams {
  int dim = 3;
  Real h = 0;      // smoothing length
  Real alpha = 0;  // alpha_D
  Real inv_h = 0;
};

inline KernelParams make_kernel(int dim, Real h) {
  KernelParams k;
  k.dim = dim;
  k.h = h;
  k.inv_h = Real(1) / h;
  k.alpha = dim == 2 ? Real(7) / (Real(4) * kPi * h * h) : Real(21) / (Real(16) * kPi * h * h * h);
  return k;
}

// W and F = (dW/dr) / r together, so that grad_i W(r_ij) = r_ij * F. dW/dq = -5 alpha q
// (1 - q/2)^3, which gives F = -5 alpha (1 - q/2)^3 / h^2 (finite at r = 0). The one place the
// kernel is written: kernel_w and kernel_f call it, and inlined, the unused half is dropped.
SPHDEM_HD inline void kernel_wf(const KernelParams& k, Real r, Real& w, Real& f) {
  const Real q = r * k.inv_h;
  if (q >= Real(2)) {
    w = f = Real(0);
    return;
  }
  const Real a = Real(1) - Real(0.5) * q;
  const Real a3 = k.alpha * a * a * a;
  w = a3 * a * (Real(2) * q + Real(1));
  f = Real(-5) * a3 * k.inv_h * k.inv_h;
}

// W(r, h).
SPHDEM_HD inline Real kernel_w(const KernelParams& k, Real r) {
  Real w, f;
  kernel_wf(k, r, w, f);
  return w;
}

// F(r).
SPHDEM_HD inline Real kernel_f(const KernelParams& k, Real r) {
  Real w, f;
  kernel_wf(k, r, w, f);
  return f;
}

}  // namespace sphdem
