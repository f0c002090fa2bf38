#!/usr/bin/env python3
"""Diesel-like cylinder pressure for the slider-crank of Tromme et al. section 5.

The paper uses measured pressure data that are not published. This script builds a
documented substitute from a single-zone, closed-cycle model of a four-stroke diesel:

* kinematics of the same slider-crank (crank radius r, centre distance l) give the cylinder
  volume V(theta) for a bore D and a compression ratio eps;
* compression from intake-valve closing (cycle angle 0 = bottom dead centre, the start of the
  compression stroke) is polytropic; combustion releases heat with a double Wiebe law
  (a premixed and a diffusion part) starting 14 deg before firing top dead centre (cycle 180 deg);
  the first law for a closed system with a constant polytropic exponent,
      dp/dphi = (n - 1)/V dQ/dphi - n p/V dV/dphi,
  is integrated with RK4 up to exhaust-valve opening;
* blowdown, exhaust stroke, intake stroke: smooth blends toward 1.1 bar (exhaust) and 0.95 bar
  (intake), back to the intake pressure at 720 deg.

The heat released is scaled so that the gas force at firing top dead centre is the inertia force
of the piston at top dead centre divided by 0.09: the paper states that inertia forces are about
9 % of the loading at firing top dead centre. The inertia force is the closed form
m_p r w^2 (1 + r/l) of the piston mass at 4000 rpm.

Output: pressure.csv, columns cycle angle [deg] and gauge pressure [Pa] (absolute minus the
1 bar acting on the crankcase side), every 1 deg from 0 to 720; 0 at both ends, so the table
is held at 0 before the cycle starts (crank acceleration and settling).
Usage: python3 make_pressure.py [-o pressure.csv]
"""
import argparse
import math

# slider-crank (data/slider_crank/*.json)
r, l = 0.045, 0.1356          # crank radius, centre distance [m]
m_piston = 0.456              # [kg]
rpm = 4000.0
# engine (chosen: a 0.5 l, naturally aspirated direct-injection diesel cylinder)
D = 0.084                     # bore [m]
eps = 17.5                    # compression ratio
p_ivc = 1.0e5                 # pressure at intake-valve closing [Pa]
p_atm = 1.0e5
p_exh, p_int = 1.1e5, 0.95e5
n_poly = 1.35                 # polytropic exponent
soc, evo = 166.0, 310.0       # start of combustion, exhaust-valve opening [cycle deg]
ratio = 0.09                  # inertia / gas force at firing TDC (paper, section 5.1)

A = math.pi * D * D / 4
Vd = A * 2 * r
Vc = Vd / (eps - 1)


def volume(phi_deg):
    th = math.radians(phi_deg + 180.0)  # crank angle from top dead centre (phi = 0 is BDC)
    x = r * math.cos(th) + math.sqrt(l * l - (r * math.sin(th)) ** 2)
    return Vc + A * (r + l - x)


def wiebe_rate(phi, start, dur, a=5.0, m=2.0):
    if phi <= start or phi >= start + dur:
        return 0.0
    z = (phi - start) / dur
    return a * (m + 1) / dur * z ** m * math.exp(-a * z ** (m + 1))


def heat_rate(phi, Q):
    # 40 % premixed (15 deg), 60 % diffusion (50 deg, starting 3 deg later)
    return Q * (0.40 * wiebe_rate(phi, soc, 15.0, m=1.0) + 0.60 * wiebe_rate(phi, soc + 3.0, 50.0, m=1.2))


def closed_cycle(Q, dphi=0.05):
    """Pressure from 0 to evo (deg) by RK4; returns the list sampled every 1 deg."""
    def f(phi, p):
        V = volume(phi)
        dV = (volume(phi + 1e-4) - volume(phi - 1e-4)) / 2e-4
        return (n_poly - 1) / V * heat_rate(phi, Q) - n_poly * p / V * dV
    out = {0: p_ivc}
    p, phi = p_ivc, 0.0
    steps = int(round(1.0 / dphi))
    for k in range(int(evo)):
        for _ in range(steps):
            k1 = f(phi, p)
            k2 = f(phi + dphi / 2, p + dphi / 2 * k1)
            k3 = f(phi + dphi / 2, p + dphi / 2 * k2)
            k4 = f(phi + dphi, p + dphi * k3)
            p += dphi / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            phi += dphi
        out[k + 1] = p
    return out


def blend(x, x0, x1):
    """0 at x0, 1 at x1, C1 (cosine)"""
    s = min(max((x - x0) / (x1 - x0), 0.0), 1.0)
    return 0.5 - 0.5 * math.cos(math.pi * s)


def cycle(Q):
    cc = closed_cycle(Q)
    p_evo = cc[int(evo)]
    table = []
    for k in range(721):
        if k <= evo:
            p = cc[k]
        elif k <= 540:
            # blowdown to the exhaust back pressure within 60 deg, then constant
            p = p_exh + (p_evo - p_exh) * math.exp(-(k - evo) / 12.0)
        else:
            # valve overlap around 540, intake stroke, back to p_ivc at 720
            p = p_exh + (p_int - p_exh) * blend(k, 530, 570)
            p = p + (p_ivc - p_int) * blend(k, 680, 720)
        table.append((k, p - p_atm))
    return table


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="pressure.csv")
    args = ap.parse_args()
    w = rpm * 2 * math.pi / 60
    f_inertia = m_piston * r * w * w * (1 + r / l)
    f_gas_target = f_inertia / ratio
    # secant on the heat released so that the gauge force at firing TDC (180 deg) hits the target
    def force_at_tdc(Q):
        return (closed_cycle(Q)[180] - p_atm) * A
    q0, q1 = 500.0, 900.0
    f0, f1 = force_at_tdc(q0) - f_gas_target, force_at_tdc(q1) - f_gas_target
    for _ in range(30):
        q2 = q1 - f1 * (q1 - q0) / (f1 - f0)
        q0, f0, q1 = q1, f1, q2
        f1 = force_at_tdc(q1) - f_gas_target
        if abs(f1) < 1e-6 * f_gas_target:
            break
    table = cycle(q1)
    peak = max(table, key=lambda t: t[1])
    with open(args.output, "w") as fh:
        fh.write("# gauge cylinder pressure, generated by make_pressure.py (see its docstring)\n")
        fh.write(f"# bore {D} m (area {A:.6e} m^2), compression ratio {eps}, heat released {q1:.2f} J\n")
        fh.write(f"# piston inertia force at TDC {f_inertia:.1f} N, gas force at firing TDC {table[180][1] * A:.1f} N "
                 f"(ratio {f_inertia / (table[180][1] * A):.4f}); peak {peak[1] / 1e5:.2f} bar gauge at {peak[0]} deg\n")
        fh.write("# cycle_angle_deg, gauge_pressure_Pa (0 deg = bottom dead centre before compression, 180 = firing TDC)\n")
        for k, p in table:
            fh.write(f"{k}, {p:.6e}\n")
    print(f"heat released {q1:.2f} J; inertia {f_inertia:.1f} N; gas force at TDC {table[180][1] * A:.1f} N; "
          f"peak {peak[1] / 1e5:.2f} bar gauge at {peak[0]} deg -> {args.output}")


if __name__ == "__main__":
    main()
