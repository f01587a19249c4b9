"""The crack-growth problems of section 4: a mode I crack driven at constant nominal K
through a row of tough asperities (``asperity_row``) or a plane of random toughness
(``random_toughness``), with their masks and fields (see docs/reference/scenes.md)."""
from __future__ import annotations

import numpy as np

from ..errors import check_positive
from ..laws import LinearCohesive
from ..model.grid import Grid
from ..model.loading import Loading
from ..model.record import Record
from ..model.scene import Numerics, Scene
from .common import UNIT, require


def cohesive_zone_size(material, tau_c, delta_c):
    """Static size of the cohesive zone of the linear cohesive law in mode I,
    R0 = (9 pi / 32) E' G_c / tau_c^2 with E' = 2 mu / (1 - nu) and G_c = tau_c delta_c / 2,
    i.e. R0 = (9 pi / 32) mu delta_c / ((1 - nu) tau_c) (Rice 1980, stress falling
    linearly across the zone). A crack running at speed v has a shorter zone."""
    return 9.0 * np.pi / 32.0 * material.mu * delta_c / ((1.0 - material.nu) * tau_c)


def _crack_setup(*, Z, n1, n3, tau_c, delta_c, cohesive_zone, g0_ratio, l0, barrier_width, symmetric,
                 material):
    """Grid, initial crack, barrier and constant-K load shared by the section 4 builders.

    Domain [0, 2Z) x [0, Z). The initial crack holds the nodes 0 <= x1 < l0 and, when
    ``symmetric``, also -l0 <= x1 < 0, i.e. [2Z - l0, 2Z) across the periodic boundary:
    then l0 is the half length of the crack, as in G0 = pi (1 - nu) tau0^2 l0 / (2 mu).
    The barrier is the bonded band of width ``barrier_width`` just behind the crack's back
    end (x1 = 0, or -l0), across the periodic boundary. Returns the pieces and the load,
    whose reference length (Loading.l0) is the initial mean crack length the stepper
    measures (count of broken nodes times dx1): l0, or 2 l0 when symmetric."""
    Z = check_positive("Z", Z)
    mat = material or UNIT
    grid = Grid(n1=n1, n3=n3, L1=2.0 * Z, L3=Z)
    tau_c = check_positive("tau_c", tau_c)
    if delta_c is None:
        cz = check_positive("cohesive_zone", cohesive_zone)
        delta_c = cz * Z * 32.0 * (1.0 - mat.nu) * tau_c / (9.0 * np.pi * mat.mu)
    delta_c = check_positive("delta_c", delta_c)
    l0 = 0.25 * Z if l0 is None else check_positive("l0", l0)
    width = 0.25 * Z if barrier_width is None else check_positive("barrier_width", barrier_width)
    back = l0 if symmetric else 0.0          # length of crack behind x1 = 0
    require("barrier_width", width >= grid.dx1,
             f"must be at least one cell (dx1 = {grid.dx1:g}), got {width:g}")
    room = 2.0 * Z - width - back - grid.dx1
    require("l0", grid.dx1 <= l0 <= room,
             f"must be in [dx1, 2Z - barrier_width - back - dx1] = [{grid.dx1:g}, {room:g}], got {l0:g}")
    g0_ratio = check_positive("g0_ratio", g0_ratio)
    eps = 1e-9 * grid.dx1
    x1 = np.broadcast_to(grid.x1[:, None], grid.shape)
    crack = (x1 < l0 - eps) | (x1 >= 2.0 * Z - back - eps)
    barrier = (x1 >= 2.0 * Z - back - width - eps) & ~crack
    l_ref = float(np.count_nonzero(crack[:, 0])) * grid.dx1
    return mat, grid, tau_c, delta_c, l0, l_ref, crack, barrier, g0_ratio


def _constant_K_load(mat, G0, l0, l_ref):
    """tau0 with G0 = pi (1 - nu) tau0^2 l0 / (2 mu) (section 4), held at constant nominal K:
    scaled by sqrt(l_ref / l(t)), l the mean crack length and l_ref its initial value."""
    tau0 = float(np.sqrt(2.0 * mat.mu * G0 / (np.pi * (1.0 - mat.nu) * l0)))
    return tau0, Loading(tau0_2=tau0, constant_K=True, l0=l_ref)


def _check_load(tau0, tau_c_min):
    require("g0_ratio", tau0 < tau_c_min,
             f"gives a load tau0 = {tau0:g} >= the weakest strength {tau_c_min:g}, which breaks the whole "
             f"plane at once; use a smaller g0_ratio or cohesive_zone (tau0 grows with sqrt(delta_c / l0))")


def asperity_row(*, Z=1.0, n1=512, n3=256, beta=None, t_end=3.0, tau_c=1.0, delta_c=None,
                 cohesive_zone=0.1, g0_ratio=1.25, l0=None, asperities=True, contrast=3.0,
                 diameter=None, n_asperities=2, centres=None, x1_asperity=0.578,
                 barrier_width=None, symmetric=True, material=None, record=None, numerics=None):
    """Mode I crack meeting a periodic row of tough circular asperities (section 4, Figs. 12-13).

    Domain X x Z = 2Z x Z on an n1 x n3 grid (512 x 256 in the paper), mu = c_s = 1,
    nu = 0.25 unless ``material`` is given. Linear cohesive law (``tau_c``, ``delta_c``);
    ``delta_c`` defaults to the value whose static cohesive zone (``cohesive_zone_size``)
    is ``cohesive_zone`` * Z (0.1 Z, 26 cells at 512 x 256: the zone of the running crack
    is then ~14 cells, 0.055 Z, the paper's figure; see docs/reference/scenes.md).
    Initial straight crack across x3 with its front at x1 = l0 = Z/4: 0 <= x1 < l0 with
    ``symmetric=False`` (the paper's words), -l0 <= x1 < l0 (across the periodic boundary)
    with ``symmetric=True``, the default: only then is G0 below the crack's actual static
    energy release rate (see docs/reference/scenes.md). A bonded barrier of width ``barrier_width``
    (Z/4) just behind the crack's back end, across the periodic boundary, stops growth in
    -x1. Uniform load tau0 held at constant nominal K (Loading(constant_K=True)) with
    G0 = pi (1 - nu) tau0^2 l0 / (2 mu) = ``g0_ratio`` * Gc, Gc = tau_c delta_c / 2.
    Asperities: ``n_asperities`` disks of ``diameter`` (Z/8) centred at x1 = ``x1_asperity`` * Z,
    x3 = (k + 1/2) Z / n_asperities (or at the (x1, x3) ``centres``), where tau_c is
    multiplied by ``contrast`` (3) and delta_c kept. ``asperities=False`` or contrast = 1
    is the uniform case (then n3 = 1, the plane problem, is allowed too)."""
    mat, grid, tau_c, delta_c, l0, l_ref, crack, barrier, g0_ratio = _crack_setup(
        Z=Z, n1=n1, n3=n3, tau_c=tau_c, delta_c=delta_c, cohesive_zone=cohesive_zone,
        g0_ratio=g0_ratio, l0=l0, barrier_width=barrier_width, symmetric=symmetric, material=material)
    Z = float(Z)
    contrast = check_positive("contrast", contrast)
    strength = tau_c
    if asperities and contrast != 1.0:
        require("asperities", not grid.plane, "need a 3D grid (n3 > 1); use asperities=False with n3 = 1")
        d = Z / 8.0 if diameter is None else check_positive("diameter", diameter)
        if centres is None:
            require("n_asperities", isinstance(n_asperities, (int, np.integer)) and n_asperities >= 1,
                     f"must be an integer >= 1, got {n_asperities!r}")
            xa = check_positive("x1_asperity", x1_asperity) * Z
            centres = [(xa, (k + 0.5) * Z / n_asperities) for k in range(int(n_asperities))]
        mask = asperity_mask(grid, centres, d)
        require("centres", np.any(mask), "no grid node falls inside an asperity")
        require("centres", not np.any(mask & (crack | barrier)),
                 "asperities must not overlap the initial crack or the barrier")
        strength = np.where(mask, contrast * tau_c, tau_c)
    Gc = 0.5 * tau_c * delta_c
    tau0, loading = _constant_K_load(mat, g0_ratio * Gc, l0, l_ref)
    _check_load(tau0, tau_c if contrast >= 1 else contrast * tau_c)
    law = LinearCohesive(tau_c=strength, delta_c=delta_c, initial_crack=crack, bonded=barrier)
    uniform = np.ndim(strength) == 0
    return Scene(material=mat, grid=grid, law=law, loading=loading, t_end=t_end, beta=beta,
                 record=record or Record(fields=("delta_2",)), numerics=numerics or Numerics(),
                 name="asperity_row_uniform" if uniform else "asperity_row")


def asperity_mask(grid, centres, diameter):
    """Nodes within diameter/2 of any of the (x1, x3) ``centres``; distances are periodic."""
    x1, x3 = np.meshgrid(grid.x1, grid.x3, indexing="ij")
    mask = np.zeros(grid.shape, dtype=bool)
    for c1, c3 in centres:
        d1 = np.abs(x1 - c1) % grid.L1
        d3 = np.abs(x3 - c3) % grid.L3
        d1, d3 = np.minimum(d1, grid.L1 - d1), np.minimum(d3, grid.L3 - d3)
        mask |= np.hypot(d1, d3) <= 0.5 * diameter * (1 + 1e-12)
    return mask


COVARIANCES = ("gaussian", "exponential")
DISTRIBUTIONS = ("lognormal", "normal")


def random_field(grid, *, correlation_length, covariance="gaussian", seed=0):
    """Correlated Gaussian random field on the periodic grid: sample mean 0, sample std 1.

    White noise from ``numpy.random.default_rng(seed)`` filtered in Fourier space by the
    square root of the spectrum of the (periodised) covariance C(r): exp(-(r/l)^2)
    ("gaussian") or exp(-r/l) ("exponential"); either way the correlation falls to 1/e
    at r = l = ``correlation_length``. Same seed, same field."""
    ell = check_positive("correlation_length", correlation_length)
    require("covariance", covariance in COVARIANCES, f"must be one of {COVARIANCES}, got {covariance!r}")
    require("seed", isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0,
             f"must be an integer >= 0, got {seed!r}")
    d1 = np.minimum(grid.x1, grid.L1 - grid.x1)
    d3 = np.minimum(grid.x3, grid.L3 - grid.x3) if not grid.plane else np.zeros(1)
    r = np.hypot(d1[:, None], d3[None, :])
    cov = np.exp(-((r / ell) ** 2)) if covariance == "gaussian" else np.exp(-r / ell)
    spectrum = np.clip(np.fft.fft2(cov).real, 0.0, None)
    white = np.random.default_rng(int(seed)).standard_normal(grid.shape)
    g = np.fft.ifft2(np.fft.fft2(white) * np.sqrt(spectrum)).real
    g -= g.mean()
    std = g.std()
    require("correlation_length", std > 0, f"is too long for the domain, got {ell:g}")
    return g / std


def _shape_field(g, mean, cov, distribution):
    """Field with sample mean ``mean`` and sample coefficient of variation ``cov`` (std/mean)."""
    if cov == 0:
        return np.full(g.shape, float(mean))
    if distribution == "normal":
        out = mean * (1.0 + cov * g)
        require("cov", out.min() > 0, f"with distribution='normal' the field reaches {out.min():g} <= 0; "
                                       f"use a smaller cov or distribution='lognormal'")
        return out
    from scipy.optimize import brentq

    def cv(s):
        e = np.exp(s * (g - g.max()))
        return e.std() / e.mean() - cov

    hi = np.sqrt(np.log1p(cov**2))
    while cv(hi) < 0:
        hi *= 2.0
        require("cov", hi < 1e3, f"is out of reach for this sample, got {cov:g}")
    s = brentq(cv, 0.0, hi, xtol=1e-14, rtol=1e-15)
    e = np.exp(s * (g - g.max()))
    return e * (mean / e.mean())


def random_toughness(*, Z=1.0, n1=512, n3=256, beta=None, t_end=3.0, tau_c=1.0, delta_c=None,
                     cohesive_zone=0.1, g0_ratio=1.25, l0=None, quantity="tau_c", mean=None,
                     cov=0.2, correlation_length=None, covariance="gaussian",
                     distribution="lognormal", seed=0, barrier_width=None, symmetric=True,
                     material=None, record=None, numerics=None):
    """Mode I crack through a plane of random toughness, on the geometry of ``asperity_row``
    (same domain, initial crack, barrier and constant-K load; G0 = ``g0_ratio`` * mean Gc).

    ``quantity="tau_c"``: tau_c varies, delta_c = ``delta_c`` is uniform (Gc follows tau_c,
    as in the asperities). ``quantity="Gc"``: Gc = tau_c delta_c / 2 varies with tau_c
    uniform, i.e. delta_c varies (and so does the cohesive zone). The field has sample
    mean ``mean`` (default: the uniform tau_c, or tau_c delta_c / 2) and sample
    coefficient of variation ``cov`` = std/mean, exactly; it is ``random_field`` (Gaussian
    or exponential covariance with 1/e length ``correlation_length``, default Z/16, from
    ``seed``) mapped by exp (``distribution="lognormal"``, always positive) or linearly
    (``"normal"``)."""
    mat, grid, tau_c, delta_c, l0, l_ref, crack, barrier, g0_ratio = _crack_setup(
        Z=Z, n1=n1, n3=n3, tau_c=tau_c, delta_c=delta_c, cohesive_zone=cohesive_zone,
        g0_ratio=g0_ratio, l0=l0, barrier_width=barrier_width, symmetric=symmetric, material=material)
    require("quantity", quantity in ("tau_c", "Gc"), f"must be 'tau_c' or 'Gc', got {quantity!r}")
    require("distribution", distribution in DISTRIBUTIONS, f"must be one of {DISTRIBUTIONS}, got {distribution!r}")
    cov = check_positive("cov", cov, allow_zero=True)
    ell = float(Z) / 16.0 if correlation_length is None else correlation_length
    g = random_field(grid, correlation_length=ell, covariance=covariance, seed=seed)
    default_mean = tau_c if quantity == "tau_c" else 0.5 * tau_c * delta_c
    mean = default_mean if mean is None else check_positive("mean", mean)
    field = _shape_field(g, mean, cov, distribution)
    if quantity == "tau_c":
        law = LinearCohesive(tau_c=field, delta_c=delta_c, initial_crack=crack, bonded=barrier)
        Gc_mean = 0.5 * float(field.mean()) * delta_c
        weakest = float(field.min())
    else:
        law = LinearCohesive(tau_c=tau_c, delta_c=2.0 * field / tau_c, initial_crack=crack, bonded=barrier)
        Gc_mean = float(field.mean())
        weakest = tau_c
    tau0, loading = _constant_K_load(mat, g0_ratio * Gc_mean, l0, l_ref)
    _check_load(tau0, weakest)
    return Scene(material=mat, grid=grid, law=law, loading=loading, t_end=t_end, beta=beta,
                 record=record or Record(fields=("delta_2",)), numerics=numerics or Numerics(),
                 name="random_toughness")
