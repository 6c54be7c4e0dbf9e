#!/usr/bin/env python3
"""Weak- and strong-scaling model for sphdem on 8-512 GPUs (docs/SCALING.md).

Every input is a stated parameter (change them on the command line); nothing here is measured on
a GPU. Per step and per rank:
  t_compute = n / R                      R: particle-steps/s of one GPU on the full step
  halo      = n * g(n)                   halo particles per owned particle for a cubic box, halo
                                         width w = 2.02 h = 2.02 * 1.2 * sqrt(3) dp (as the solver)
  t_comm    = exchanges * (latency * neighbours
              + halo * bytes_per_particle * (2 / B_pcie + 1 / B_net))
              + reductions * allreduce(P)
The halo leaves through the host (Debian's Open MPI is not CUDA-aware): device->host, network,
host->device. Efficiency = t_compute / (t_compute + t_comm) (no overlap of communication with
computation: the solver does not overlap yet).

  python3 jobs/scaling_model.py [--rate 3e8] [--net 25e9] [--pcie 25e9] [--latency 2e-6]
"""
import argparse
import math


def halo_ratio(n, width_dp):
    """Halo particles per owned particle for a cube of n particles (lattice spacing dp)."""
    side = n ** (1.0 / 3.0)
    return ((side + 2 * width_dp) ** 3 - side ** 3) / side ** 3


def step_time(n, p, a):
    width_dp = 2.02 * 1.2 * math.sqrt(3)
    halo = n * halo_ratio(n, width_dp) if p > 1 else 0.0
    t_comp = n / a.rate
    per_exchange = 26 * a.latency + halo * a.bytes * (2.0 / a.pcie + 1.0 / a.net)
    t_red = a.reductions * 2 * math.log2(max(p, 2)) * a.latency if p > 1 else 0.0
    t_comm = (a.exchanges * per_exchange + t_red) if p > 1 else 0.0
    return t_comp, t_comm, halo


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--rate", type=float, default=1.5e8,
                    help="particle-steps/s of one GPU, full step (default: the FP64 H100 target)")
    ap.add_argument("--net", type=float, default=25e9, help="network bytes/s per GPU (HDR IB 200 Gb/s)")
    ap.add_argument("--pcie", type=float, default=25e9, help="host<->device bytes/s (PCIe 4 x16, achieved)")
    ap.add_argument("--latency", type=float, default=2e-6, help="per message, s")
    ap.add_argument("--bytes", type=float, default=56.0,
                    help="bytes per halo particle per exchange (pos, vel, rho in FP64)")
    ap.add_argument("--exchanges", type=float, default=2.0,
                    help="halo exchanges per step (rebuild + refresh; 3 with rheology)")
    ap.add_argument("--reductions", type=float, default=3.0, help="allreduces per step")
    a = ap.parse_args()

    print(f"# rate {a.rate:.3g} particle-steps/s per GPU, net {a.net:.3g} B/s, pcie {a.pcie:.3g} B/s,"
          f" latency {a.latency:.3g} s, {a.bytes:g} B per halo particle, {a.exchanges:g} exchanges/step")
    print("\n## Weak scaling (particles per GPU fixed; efficiency independent of P beyond the allreduce)")
    print("| particles/GPU | halo/owned | t_compute ms | t_comm ms (P=8) | eff P=8 | eff P=64 | eff P=512 |")
    print("|---|---|---|---|---|---|---|")
    for n in [1e4, 3e4, 1e5, 3e5, 1e6, 3e6, 1e7]:
        effs = []
        for p in [8, 64, 512]:
            tc, tm, halo = step_time(n, p, a)
            effs.append(tc / (tc + tm))
        tc, tm, halo = step_time(n, 8, a)
        print(f"| {n:.0e} | {halo / n:.2f} | {tc * 1e3:.3f} | {tm * 1e3:.3f} | "
              + " | ".join(f"{e:.2f}" for e in effs) + " |")
    # Where weak-scaling efficiency crosses 0.9 at P = 64.
    lo, hi = 1e3, 1e9
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        tc, tm, _ = step_time(mid, 64, a)
        if tc / (tc + tm) < 0.9:
            lo = mid
        else:
            hi = mid
    print(f"\nEfficiency falls below 90% under about {hi:.3g} particles per GPU (P = 64).")

    print("\n## Strong scaling (total fixed)")
    print("| total | GPUs | particles/GPU | ms/step | speed-up | efficiency |")
    print("|---|---|---|---|---|---|")
    for total in [3.6e6, 1e8]:
        t1 = total / a.rate
        for p in [8, 16, 32, 64, 128, 256, 512]:
            n = total / p
            tc, tm, _ = step_time(n, p, a)
            t = tc + tm
            print(f"| {total:.2g} | {p} | {n:.3g} | {t * 1e3:.3f} | {t1 / t:.1f} | {t1 / t / p:.2f} |")


if __name__ == "__main__":
    main()
