"""Energy budget of a run, from quantities on the plane only.

With Eq. (3), tau_j = tau0_j + tau'_j, tau'_j = -eta_j v_j + f_j the traction of the
field set up by the slip/opening delta on the plane. The power the traction of that
field takes out of the two half spaces is  int tau'.v dA , so that, identically,

    W = D + E_pert,      W = int int tau0 . v dA dt   (work of the loads on the plane)
                         D = int int tau  . v dA dt   (dissipated by the interface)
                    E_pert = -int int tau'. v dA dt   (energy put into the half spaces)

and E_pert splits into the static strain energy of the current delta and the rest:

    E_pert = U(delta(t)) + E_dyn,   U(delta) = 1/2 int delta . K delta dA,

K the static stiffness of the two half spaces together. In Fourier space (Eqs. 23,
29-34; velocity formulation Eq. 33, F = -(mu q/2) Z(0) D + dynamic part):

    K_I = K_II = (mu q / 2) Z(0) = mu q / (2 (1 - nu)),    K_III = (mu q / 2) Z_III(0) = mu q / 2,

Z(0) = int_0^inf C dT (``kernels.static_integral``; not C(0) = ``kernels.C0``, the
instantaneous value). The factor 1/2 in mu q/2 is the two half spaces in series:
each carries u = +-delta/2 with a stiffness mu q / (1 - nu) on its own face. In 3D the
shear components are rotated into the II and III channels of each mode (Eq. 28);
in the plane problem (n3 == 1) delta_1 is mode II, delta_3 mode III, and every energy
is per unit length along x3 (the cell area is dx1, not dx1 dx3).

E_dyn is the kinetic plus dynamic strain energy of the half spaces: the energy
radiated as waves, plus, while the plane still moves, the near-field part still bound
to it (plane quantities cannot separate the two: they agree once the plane is at rest).
It is estimated twice:

* ``radiated_balance`` = W - dU - D, from the recorded traction (the engine's f);
* ``radiated_flux`` = int int (eta v^2 - f_dyn . v) dA dt, the power of the
  radiation-damping term and of the dynamic part of f, with f_dyn recomputed here from
  the recorded slip history alone, f_dyn = (mu q/2) int_0^t Z(q c_s (t - t')) V(t') dt'
  (Eq. 33) with the closed-form kernels, independently of the engine, its formulation
  and the recorded traction.

The slip history is taken as piecewise linear between the recorded snapshots
(V = (delta_{k+1} - delta_k)/h on each interval), for which the flux estimate is exact
up to Simpson's rule on the interval averages of int Z. ``closure`` is their difference
over the largest |W| of the run.

What must be recorded (``energy_record``): delta_j and tau_j of every active component
on the whole plane from t = 0 (no region), best every step (``every=1``): with a coarser
cadence the flux estimate sees V averaged over several steps (the closure grows about
linearly with the cadence), and the interface work int tau d delta is a trapezoid over
the interval. Snapshots at uneven times give no flux estimate (NaN). v_j is used too, for the
"trapezoid" rule only (``energy_record(..., velocities=True)``).
"""
from __future__ import annotations

import numpy as np
import scipy.fft as sfft
import xarray as xr

from ..elastic import kernels
from ..errors import InputError
from ..laws.base import cell_area_and_width, failed_length
from ..model.record import Record
from ..solver.halfspace import active_channels, split_channels
from ..solver.interfaces import interface_type

__all__ = ["energy_record", "energy_budget", "strain_energy", "static_stiffness", "budget_summary"]

NAMES = {
    "work_loads": "work of the loads, int int tau0 . v dA dt",
    "strain_energy": "change of the static strain energy of the half spaces, 1/2 int delta . K delta dA",
    "dissipation": "energy dissipated by the interface, int int tau . v dA dt",
    "fracture_energy": "fracture energy (breakdown work above the residual strength) from the law",
    "frictional_heat": "dissipation minus fracture energy (frictional heat; contact work for cohesive laws)",
    "radiation_damping": "int int eta v^2 dA dt",
    "radiated_balance": "radiated (wave) energy from the balance W - dU - D",
    "radiated_flux": "radiated (wave) energy from the flux int int (eta v^2 - f_dyn . v) dA dt",
    "closure": "(radiated_balance - radiated_flux) / max |W|",
}


# ----------------------------------------------------------------------------- recording
def energy_record(scene, *, every: int = 1, stations=None, velocities: bool = False) -> Record:
    """The Record ``energy_budget`` needs for ``scene`` (a Scene, or a tuple of active
    components): delta_j and tau_j of every active component on the whole plane, every
    ``every`` steps (1 is best), plus v_j when ``velocities`` (only the "trapezoid" rule
    uses them). Keeps the scene's stations unless ``stations`` is given."""
    if isinstance(scene, (tuple, list)):
        comps = tuple(scene)
    else:
        comps = scene.components
        if stations is None:
            stations = scene.record.stations
    fields = [f"delta_{c}" for c in comps] + [f"tau_{c}" for c in comps]
    if velocities:
        fields += [f"v_{c}" for c in comps]
    return Record(fields=tuple(fields), every=every, stations=stations)


# ----------------------------------------------------------------------------- statics
class _Spectral:
    """Transforms, Parseval weights and channel rotation of one grid."""

    def __init__(self, grid, material, comps):
        self.grid, self.mat, self.comps = grid, material, tuple(comps)
        # own layout (independent of the engine's): rfft along x1, full fft along x3
        k1 = 2 * np.pi * np.fft.rfftfreq(grid.n1, d=grid.dx1)
        m1 = 2 * np.pi * np.fft.fftfreq(grid.n3, d=grid.dx3) if not grid.plane else np.zeros(1)
        k, m = np.meshgrid(k1, m1, indexing="ij")
        self.shape = k.shape
        q = np.sqrt(k**2 + m**2)
        self.q = q
        with np.errstate(invalid="ignore", divide="ignore"):
            self.c = np.where(q > 0, k / q, 0.0)
            self.s = np.where(q > 0, m / q, 0.0)
        n1 = grid.n1
        w = np.full(self.shape, 2.0)
        w[0] = 1.0
        if n1 % 2 == 0:
            w[n1 // 2] = 1.0
        self.w = w                              # Parseval weights of the half spectrum
        self.N = grid.n1 * grid.n3
        self.dA = grid.dx1 * (1.0 if grid.plane else grid.dx3)
        self.shear3d = (not grid.plane) and any(c in comps for c in (1, 3))
        nu = material.nu
        self.channels = active_channels(grid.plane, comps)
        self.K = {ch: 0.5 * material.mu * q * kernels.static_integral(ch, nu) for ch in self.channels}

    def forward(self, a):
        """(..., n1, n3) real -> (..., n1//2+1, n3) complex, rfft along x1, fft along x3."""
        X = np.fft.rfft(a, axis=-2)
        if not self.grid.plane:
            X = np.fft.fft(X, axis=-1)
        return X

    def split(self, X: dict) -> dict:
        return split_channels(X, self.channels, self.shear3d, self.c, self.s)

    def dot(self, A, B):
        """int a b dA from the half spectra of a and b (sums over the last two axes)."""
        return self.dA / self.N * np.sum(self.w * (A.conj() * B).real, axis=(-2, -1))

    def energy(self, delta: dict):
        """1/2 int delta . K delta dA; ``delta`` maps component -> (..., n1, n3)."""
        D = self.split({c: self.forward(np.asarray(delta[c], dtype=float)) for c in delta})
        return 0.5 * sum(self.dA / self.N * np.sum(self.w * self.K[ch] * np.abs(D[ch]) ** 2, axis=(-2, -1))
                         for ch in D)


def static_stiffness(grid, material, components=(2,)) -> dict:
    """Static stiffness K(q) of the two half spaces per channel ("I", "II", "III") on the
    half-spectrum layout of ``grid``: traction = -K D for a static delta = D e^{i q.x}."""
    return dict(_Spectral(grid, material, components).K)


def strain_energy(delta: dict, grid, material):
    """Static strain energy 1/2 int delta . K delta dA of the two half spaces for the
    displacement discontinuity ``delta`` {component: array (..., n1, n3)} (per unit length
    along x3 in the plane problem). Zero for a uniform delta (q = 0 carries no static energy)."""
    comps = tuple(sorted(int(c) for c in delta))
    return _Spectral(grid, material, comps).energy({int(c): v for c, v in delta.items()})


# ----------------------------------------------------------------------------- flux weights
def _simpson_weights(kernel, gamma_unique, n_int, nu, block=256):
    """w_j (n_int, U): interval average of the response of interval m on interval m + j
    to a unit piecewise-constant V, in units of mu/(2 c_s): A(j) - A(j-1), A(j) the
    average of Zi = int_0^T Z over T in [j gamma, (j+1) gamma] by Simpson's rule."""
    U = gamma_unique.size
    out = np.empty((n_int, U))
    jj = np.arange(2 * n_int + 1) * 0.5
    for lo in range(0, U, block):
        g = gamma_unique[lo:lo + block]
        Zi = np.asarray(kernels.Z_integral(kernel, jj[:, None] * g[None, :], nu)).reshape(jj.size, g.size)
        A = (Zi[0:-1:2] + 4.0 * Zi[1::2] + Zi[2::2]) / 6.0
        out[:, lo:lo + block] = np.diff(A, axis=0, prepend=0.0)
    return out


def _dynamic_power(sp, Vh: dict, h: float, chunk: int = 2048) -> np.ndarray:
    """int f_dyn . V dA averaged over each interval (n_int,), f_dyn recomputed from the
    piecewise-constant velocity spectra ``Vh`` {channel: (n_int, n1h, n3) complex}."""
    mat = sp.mat
    n_int = next(iter(Vh.values())).shape[0]
    L = sfft.next_fast_len(2 * n_int)
    gamma = (sp.q * mat.cs * h).ravel()
    key = np.round(gamma / max(gamma.max(), 1e-300), 11)
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    g_unique = gamma[first]
    wpar = np.broadcast_to(sp.w, sp.q.shape).ravel()
    power = np.zeros(n_int)
    for ch, V in Vh.items():
        W = _simpson_weights(ch, g_unique, n_int, mat.nu)
        Vf = V.reshape(n_int, -1)
        for lo in range(0, Vf.shape[1], chunk):
            sl = slice(lo, lo + chunk)
            Wf = sfft.fft(W[:, inv[sl]], L, axis=0)
            Vc = Vf[:, sl].astype(np.complex128)
            F = sfft.ifft(sfft.fft(Vc, L, axis=0) * Wf, axis=0)[:n_int]
            power += np.sum(wpar[sl] * (Vc.conj() * F).real, axis=1)
    return 0.5 * mat.mu / mat.cs * sp.dA / sp.N * power


# ----------------------------------------------------------------------------- the budget
def _cadence(t, dt):
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise ValueError("energy_budget needs at least two recorded snapshots")
    dts = np.diff(t)
    h = float(dts[0])
    uniform = np.allclose(dts, h, rtol=1e-6, atol=1e-12 * max(abs(t[-1]), 1.0))
    every = int(round(h / dt)) if uniform else None
    return h, uniform, every


def energy_budget(ds, *, scene=None, flux: bool = True, rule: str = "auto", chunk: int = 64) -> xr.Dataset:
    """Energy budget of the run ``ds`` (a cracklab Dataset recorded with ``energy_record``).

    Returns a Dataset over the recorded times ``t`` with work_loads (W), strain_energy
    (dU), dissipation (D), fracture_energy and frictional_heat (D split by the law, for
    LinearCohesive and SlipWeakening; NaN otherwise), radiation_damping, radiated_balance
    (W - dU - D), radiated_flux (independent, from the slip history and the kernels) and
    closure; and over (x1, x3) the final dissipation and fracture energy per unit area.
    Energies are relative to the first snapshot (record from t = 0).

    ``rule`` pairs tractions with slip increments: "left" (tau_k . (delta_{k+1} - delta_k),
    the displacement formulation's own pairing, used by "auto" when it is recorded every
    step), "delta" (1/2 (tau_k + tau_{k+1}) . (delta_{k+1} - delta_k); "auto" otherwise,
    e.g. the product scheme, whose delta is the trapezoid of v) or "trapezoid"
    (h/2 (tau_k . v_k + tau_{k+1} . v_{k+1}), needs v). ``flux=False`` skips the flux estimate.
    """
    if scene is None:
        from ..output.simulate import scene_of

        scene = scene_of(ds)
    grid, mat, law, load = scene.grid, scene.material, scene.law, scene.loading
    comps = scene.components
    refusal = interface_type(scene.materials).energy_refusal
    if refusal is not None:
        raise InputError("materials", refusal)
    if grid.free_surface:
        raise InputError("grid.free_surface", "energy_budget covers the periodic plane; a half plane below a "
                                              "free surface (mirror symmetry) is not implemented: run the doubled "
                                              "whole-space scene with mirrored loads for its budget")
    for name in [f"delta_{c}" for c in comps] + [f"tau_{c}" for c in comps]:
        if name not in ds:
            raise InputError("record.fields", f"energy_budget needs {name!r} recorded on the whole plane; "
                                              f"use record=cracklab.analysis.energy.energy_record(scene)")
    if ds.sizes["x1"] != grid.n1 or ds.sizes["x3"] != grid.n3:
        raise InputError("record.region", "energy_budget needs the whole plane (no region)")
    t = np.asarray(ds["t"].values, dtype=float)
    h, uniform, every = _cadence(t, scene.dt)
    if rule == "auto":
        rule = "left" if (every == 1 and scene.formulation == "displacement") else "delta"
    if rule not in ("left", "trapezoid", "delta"):
        raise ValueError(f"rule must be 'auto', 'left', 'trapezoid' or 'delta', got {rule!r}")
    has_v = all(f"v_{c}" in ds for c in comps)
    if rule == "trapezoid" and not has_v:
        raise InputError("record.fields", "rule 'trapezoid' needs v_j recorded")
    sp = _Spectral(grid, mat, comps)
    dA = sp.dA
    eta = {c: mat.eta(c) for c in comps}
    nt = t.size

    # the law's state rebuilt from the recorded slip (the law says which: Law.energy_state)
    state = law.energy_state(grid)
    area, width = cell_area_and_width(grid)     # for the crack length of constant-K loading
    l0 = None
    if load.constant_K:
        l0 = load.l0
        failed = law.energy_failed(state) if state is not None else None
        if l0 is None and failed is not None:
            l0 = failed_length(failed, area, width)

    def tau0_at(k, st):
        length = None
        failed = law.energy_failed(st) if load.constant_K and st is not None else None
        if failed is not None:
            length = failed_length(failed, area, width) or l0
        return {c: np.broadcast_to(np.asarray(v, dtype=float), grid.shape)
                for c, v in load.at(t[k], comps, length, grid).items()}

    W = np.zeros(nt)
    D = np.zeros(nt)
    U = np.zeros(nt)
    damp = np.zeros(nt)
    frac = np.full(nt, np.nan)
    d_density = np.zeros(grid.shape)
    Vh = {ch: np.zeros((nt - 1,) + sp.shape, dtype=np.complex64) for ch in sp.channels} if flux else None

    prev = None          # the last snapshot of the previous chunk: (delta, tau, v, tau0)
    for lo in range(0, nt, chunk):
        hi = min(nt, lo + chunk)
        block = {n: np.asarray(ds[n].isel(t=slice(lo, hi)).values, dtype=float)
                 for n in [f"delta_{c}" for c in comps] + [f"tau_{c}" for c in comps]
                 + ([f"v_{c}" for c in comps] if has_v else [])}
        U[lo:hi] = sp.energy({c: block[f"delta_{c}"] for c in comps})
        for i in range(hi - lo):
            k = lo + i
            dl = {c: block[f"delta_{c}"][i] for c in comps}
            ta = {c: block[f"tau_{c}"][i] for c in comps}
            ve = {c: block[f"v_{c}"][i] for c in comps} if has_v else None
            if state is not None:
                law.energy_update(state, dl, prev[0] if prev is not None else None)
            t0 = tau0_at(k, state)
            if state is not None:
                g = law.fracture_energy(state)
                frac[k] = dA * float(np.sum(g))
            if prev is not None:
                pdl, pta, pve, pt0 = prev
                dd = {c: dl[c] - pdl[c] for c in comps}
                if rule == "left":
                    dw = sum(pt0[c] * dd[c] for c in comps)
                    dD = sum(pta[c] * dd[c] for c in comps)
                elif rule == "trapezoid":
                    dw = sum(0.5 * (pt0[c] + t0[c]) * dd[c] for c in comps)
                    dD = 0.5 * (t[k] - t[k - 1]) * sum(pta[c] * pve[c] + ta[c] * ve[c] for c in comps)
                else:
                    dw = sum(0.5 * (pt0[c] + t0[c]) * dd[c] for c in comps)
                    dD = sum(0.5 * (pta[c] + ta[c]) * dd[c] for c in comps)
                hk = t[k] - t[k - 1]
                W[k] = W[k - 1] + dA * float(np.sum(dw))
                D[k] = D[k - 1] + dA * float(np.sum(dD))
                d_density += dD
                damp[k] = damp[k - 1] + dA / hk * float(sum(eta[c] * np.sum(dd[c] ** 2) for c in comps))
                if flux:
                    Vk = sp.split({c: sp.forward(dd[c] / hk) for c in comps})
                    for ch in sp.channels:
                        Vh[ch][k - 1] = Vk[ch]
            prev = (dl, ta, ve, t0)
    dU = U - U[0]
    frac = frac - frac[0] if state is not None else frac
    rad_bal = W - dU - D
    rad_flux = np.full(nt, np.nan)
    if flux and uniform:
        pdyn = _dynamic_power(sp, Vh, h)
        rad_flux = damp - np.concatenate([[0.0], np.cumsum(h * pdyn)])
    scale = float(np.max(np.abs(W))) or float(np.max(np.abs(D) + np.abs(dU))) or 1.0
    u = scene.units
    eunit = "1" if all(v == "1" for v in u.values()) else \
        (f"{u['stress']} {u['length']}2" if grid.plane else f"{u['stress']} {u['length']}3")
    if grid.plane and eunit != "1":
        eunit += f" {u['length']}-1"
    out = xr.Dataset(coords={"t": ("t", t, dict(ds["t"].attrs)), "x1": ds["x1"], "x3": ds["x3"]})
    series = {"work_loads": W, "strain_energy": dU, "dissipation": D, "fracture_energy": frac,
              "frictional_heat": D - frac, "radiation_damping": damp, "radiated_balance": rad_bal,
              "radiated_flux": rad_flux, "closure": (rad_bal - rad_flux) / scale}
    for name, arr in series.items():
        out[name] = ("t", arr, {"long_name": NAMES[name], "units": "1" if name == "closure" else eunit})
    dunit = "1" if eunit == "1" else f"{u['stress']} {u['length']}"
    out["dissipation_density"] = (("x1", "x3"), d_density,
                                  {"long_name": "energy dissipated per unit area of the plane", "units": dunit})
    if state is not None:
        out["fracture_energy_density"] = (("x1", "x3"), law.fracture_energy(state),
                                          {"long_name": "fracture energy per unit area", "units": dunit})
    out.attrs = {"scene": scene.name, "rule": rule, "cadence_steps": -1 if every is None else every,
                 "energy_scale": scale, "per_unit_length_x3": int(grid.plane)}
    return out


def budget_summary(budget: xr.Dataset) -> dict:
    """Final values and closure of a budget (floats), for tables."""
    last = budget.isel(t=-1)
    out = {n: float(last[n]) for n in ("work_loads", "strain_energy", "dissipation", "fracture_energy",
                                        "frictional_heat", "radiation_damping", "radiated_balance",
                                        "radiated_flux", "closure")}
    out["t"] = float(last["t"])
    closure = np.abs(budget["closure"].values)
    out["max_abs_closure"] = float(np.nanmax(closure)) if np.isfinite(closure).any() else float("nan")
    return out
