"""The spring-slider with radiation damping: a uniform rate-and-state fault pulled through a
spring of stiffness k at the plate rate (docs/reference/equations.md, "Sequences"), and its
independent solution: the ODE in (ln V, psi) from differentiating the friction equation in
time, solved by scipy's Radau with its event location (no root solve of the friction law)."""
from __future__ import annotations

import numpy as np

MU, CS = 30e9, 3000.0
SIGMA, A, B, L, V0, F0, VP = 50e6, 0.010, 0.015, 0.008, 1e-6, 0.6, 1e-9
K = 0.5 * SIGMA * (B - A) / L          # half the critical stiffness: stick-slip cycles
TAU0 = SIGMA * F0 + 1e5
THRESHOLD = 1e-3


def scene(t_end, tolerance=1e-8, pair="dormand_prince", evolution="ageing"):
    from cracklab import Grid, Loading, Material, RateState, Record, Scene, Sequence

    law = RateState(a=A, b=B, L=L, V0=V0, f0=F0, sigma_n=SIGMA, V_ini=VP, evolution=evolution)
    return Scene(material=Material(mu=MU, cs=CS, nu=0.25), grid=Grid(n1=4, n3=1, L1=4.0, L3=1.0), law=law,
                 loading=Loading(tau0_3=TAU0), t_end=t_end, record=Record(fields=("delta_3",), stations={"p": (0.0,)}),
                 sequence=Sequence(plate_rate_3=VP, stiffness=K, tolerance=tolerance, dt_min=1e-6, dt_max=1e8,
                                   dt_first=1.0, pair=pair))


def reference(t_end, evolution="ageing"):
    """(event start times, (peak time, peak slip rate) per event) of the ODE, Radau at rtol 1e-11."""
    from scipy.integrate import solve_ivp

    eta = MU / (2 * CS)
    y = (TAU0 - eta * VP) / (SIGMA * A)
    psi0 = A * (np.log(2 * V0 / VP) + np.log(np.sinh(y)))

    def G(V, psi):
        if evolution == "ageing":
            return (B * V0 / L) * (np.exp((F0 - psi) / B) - V / V0)
        fss = F0 - (B - A) * np.log(V / V0)
        return -(V / L) * (psi - A * np.log(2 * V0 / V * np.sinh(fss / A)))

    def rhs(t, s):
        lnV, psi = s
        V = np.exp(lnV)
        u = V / (2 * V0) * np.exp(psi / A)
        r = u / np.sqrt(1 + u * u)
        g = G(V, psi)
        dV = (K * (VP - V) - SIGMA * r * g) / (eta + SIGMA * A * r / V)
        return [dV / V, g]

    def up(t, s):
        return s[0] - np.log(THRESHOLD)
    up.direction = 1

    def peak(t, s):
        return rhs(t, s)[0]
    peak.direction = -1

    sol = solve_ivp(rhs, (0, t_end), [np.log(VP), psi0], method="Radau", rtol=1e-11, atol=[1e-11, 1e-13],
                    events=[up, peak])
    assert sol.status == 0
    peaks = [(t, np.exp(s[0])) for t, s in zip(sol.t_events[1], sol.y_events[1]) if np.exp(s[0]) > THRESHOLD]
    return np.asarray(sol.t_events[0]), np.asarray(peaks)
