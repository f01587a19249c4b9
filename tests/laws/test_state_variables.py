"""A law's state variables are recorded by name (Record(fields=...)), with their units."""
import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, LinearCohesive, Loading, Material, Record, Scene, SlipWeakening

MAT = Material(mu=1.0, cs=1.0, nu=0.25)


def test_the_slip_path_is_recorded_and_is_the_integral_of_the_slip_rate():
    """Uniform overload of mu_s = mu_d friction: v = 2 c_s (tau0 - mu sigma_n) / mu at every
    step, and the slip path after step n is n dt v (the law adds dt |v_{n-1}| at step n)."""
    tau0, mu, sn = 1.5, 0.6, 2.0
    sc = Scene(material=MAT, grid=Grid(n1=16, n3=16, L1=1.0, L3=1.0),
               law=SlipWeakening(mu_s=mu, mu_d=mu, D_c=1.0, sigma_n=sn), loading=Loading(tau0_1=tau0),
               t_end=0.5, record=Record(fields=("slip", "v_1"), every=4), units={"length": "m", "time": "s",
                                                                                   "stress": "Pa"})
    ds = cracklab.simulate(sc)
    v = 2 * MAT.cs * (tau0 - mu * sn) / MAT.mu
    np.testing.assert_allclose(ds.slip.values, (ds.t.values * v)[:, None, None] * np.ones((1, 16, 16)),
                               rtol=1e-12, atol=1e-15)
    assert ds.slip.attrs == {"long_name": "slip path", "units": "m"}


def test_a_state_variable_of_another_law_is_refused():
    with pytest.raises(InputError, match=r"^record.fields: 'slip' is not a state variable of the law "
                                         r"'linear_cohesive' \(its state variables: delta_max\)"):
        Scene(material=MAT, grid=Grid(n1=16, n3=16, L1=1.0, L3=1.0), law=LinearCohesive(tau_c=1.0, delta_c=0.1),
              loading=Loading(tau0_2=0.5), t_end=0.1, record=Record(fields=("slip",)))


def test_an_unknown_name_lists_the_state_variables():
    with pytest.raises(InputError, match=r"or a state variable of the law \(delta_max, lambda_max, psi, sigma_eff, slip\)"):
        Record(fields=("theta",))
