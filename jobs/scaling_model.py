#!/usr/bin/env python3
"""Weak- and strong-scaling model for sphdem on 8-512 GPUs (docs/SCALING.md).

Every input is a stated parameter (override on the command line); nothing here is measured on a
GPU. Per rank and step, n owned fluid particles in a cubic box:
  t_compute = n / rate                              rate: particle-steps/s of one GPU, full step
  halo      = n * g(n)                              halo per owned particle of a cube, halo width
                                                    2.02 h = 2.02 * 1.2 * sqrt(3) dp (as the solver)
Two designs:
  as-built  the code today: every step the whole particle set goes device->host->device twice
            (migration, halo build), the halo carries all 14 fields (220 B per particle), and the
            replicated walls' mDBC state (5 Reals per wall, all walls) is summed by MPI_Allreduce.
  planned   halo packed on the device (only halo bytes cross PCIe), the plan reused while the
            largest displacement stays under skin/2 (rebuild every `rebuild_every` steps),
            refreshes of pos/vel/rho (56 B), walls kept per box and synchronised like the halo.
  planned+overlap  as planned, with the halo exchange hidden behind the interior particles'
            forces (efficiency = t_compute / max(t_compute, t_comm)).
Otherwise efficiency = t_compute / (t_compute + t_comm): no overlap (the code today).

  python3 jobs/scaling_model.py [--rate 1.5e8] [--net 25e9] [--pcie 25e9] [--latency 2e-6]
"""
import argparse
import math

FIELDS_BYTES = 220.0   # id 8, seven Vec3 168, five Reals 40, body 4 (FP64)
REFRESH_BYTES = 56.0   # pos, vel, rho
WALL_BYTES = 40.0      # rho, press, vel_bc


def halo_ratio(n, width_dp):
    side = n ** (1.0 / 3.0)
    return ((side + 2 * width_dp) ** 3 - side ** 3) / side ** 3


def step_time(n, p, a, design):
    width_dp = 2.02 * 1.2 * math.sqrt(3)
    t_comp = n / a.rate
    if p == 1:
        return t_comp, 0.0, 0.0
    halo = n * halo_ratio(n, width_dp)
    msg = 26 * a.latency
    red = 3 * 2 * math.log2(p) * a.latency
    if design == "as-built":
        stage = 2 * 2 * n * FIELDS_BYTES / a.pcie            # two full round trips per step
        fill = msg + halo * FIELDS_BYTES / a.net
        walls_total = a.wall_ratio * n * p
        walls = 2 * walls_total * WALL_BYTES / a.net + 2 * math.log2(p) * a.latency
        t_comm = stage + fill + walls + red
    else:
        refresh = msg + halo * REFRESH_BYTES * (2.0 / a.pcie + 1.0 / a.net)
        rebuild = (msg + halo * FIELDS_BYTES * (2.0 / a.pcie + 1.0 / a.net)) / a.rebuild_every
        walls = msg + a.wall_ratio * halo * WALL_BYTES * (2.0 / a.pcie + 1.0 / a.net)
        t_comm = a.exchanges * refresh + rebuild + walls + red
    return t_comp, t_comm, halo


def eff(n, p, a, design):
    tc, tm, _ = step_time(n, p, a, design.replace("+overlap", ""))
    if design.endswith("+overlap"):
        return tc / max(tc, tm)
    return tc / (tc + tm)


def n90(p, a, design):
    lo, hi = 1e2, 1e12
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        if eff(mid, p, a, design) < 0.9:
            lo = mid
        else:
            hi = mid
    return hi


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--rate", type=float, default=1.5e8,
                    help="particle-steps/s of one GPU, full step (default: the FP64 H100 target)")
    ap.add_argument("--net", type=float, default=25e9, help="network B/s per GPU (HDR 200 Gb/s)")
    ap.add_argument("--pcie", type=float, default=25e9, help="host<->device B/s (PCIe 4 x16)")
    ap.add_argument("--latency", type=float, default=2e-6, help="per message, s")
    ap.add_argument("--exchanges", type=float, default=1.0,
                    help="halo refreshes per step (1 Verlet, 2 symplectic, +1 rheology)")
    ap.add_argument("--rebuild-every", type=float, default=10.0, help="steps per plan rebuild")
    ap.add_argument("--wall-ratio", type=float, default=0.84,
                    help="wall particles per fluid particle (dam_break_3d: 0.84)")
    a = ap.parse_args()
    print(f"rate {a.rate:.3g} particle-steps/s per GPU, network {a.net:.3g} B/s, PCIe {a.pcie:.3g}"
          f" B/s, latency {a.latency:.3g} s, walls/fluid {a.wall_ratio}")
    for design in ["as-built", "planned", "planned+overlap"]:
        print(f"\n## Weak scaling, {design}\n")
        print("| particles/GPU | halo/owned | t_compute ms | t_comm ms P=8 | eff P=8 | eff P=64 | eff P=512 |")
        print("|---|---|---|---|---|---|---|")
        for n in [1e5, 3e5, 1e6, 3e6, 1e7, 3e7]:
            effs = [eff(n, p, a, design) for p in [8, 64, 512]]
            tc, tm, halo = step_time(n, 8, a, design.replace("+overlap", ""))
            print(f"| {n:.0e} | {halo / n:.2f} | {tc * 1e3:.2f} | {tm * 1e3:.2f} | "
                  + " | ".join(f"{e:.2f}" for e in effs) + " |")
        print("\n90% efficiency needs at least: " + ", ".join(
            f"P={p}: {n90(p, a, design):.2g}" for p in [8, 64, 512]) + " particles per GPU")
    print("\n## Strong scaling, planned+overlap (total fixed)\n")
    print("| total | GPUs | particles/GPU | ms/step | speed-up vs 1 GPU | efficiency |")
    print("|---|---|---|---|---|---|")
    for total in [3.6e6, 1e8]:
        t1 = total / a.rate
        for p in [8, 32, 128, 512]:
            tc, tm, _ = step_time(total / p, p, a, "planned")
            t = max(tc, tm)
            print(f"| {total:.2g} | {p} | {total / p:.3g} | {t * 1e3:.3f} | {t1 / t:.1f} | {t1 / t / p:.2f} |")


if __name__ == "__main__":
    main()
