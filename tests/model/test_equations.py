"""The model's equations as the compiled paths run them (rnnpb.model.equations)."""

from pathlib import Path

import numpy as np
import pytest

from rnnpb.model import _numba, equations


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_unit_is_the_sigmoid_within_2e_7_and_keeps_nan(dtype):
    x = np.linspace(-30.0, 30.0, 20001).astype(dtype)
    exact = 1.0 / (1.0 + np.exp(-x.astype(np.float64)))
    got = np.array([equations.unit(v) for v in x])  # numba hands a float32 back as a float
    if dtype == np.float32:  # a float32 computation stays float32: its results are float32s
        np.testing.assert_array_equal(got.astype(np.float32), got)
    assert np.max(np.abs(got - exact)) < 2e-7
    assert np.isnan(equations.unit(dtype(np.nan)))
    np.testing.assert_allclose(
        [equations.tanh(v) for v in x[::100]], np.tanh(x[::100].astype(np.float64)), atol=5e-7
    )


def test_every_module_with_kernels_names_their_cache():
    """The compiled code is kept under a digest of KERNEL_MODULES' source: a module whose
    kernels are not listed would keep running old code after a change."""
    here = Path(_numba.__file__).parent
    using = {path.name for path in here.glob("*.py") if "@kernel\n" in path.read_text()}
    assert using == set(_numba.KERNEL_MODULES)


def test_sums_of_any_number_of_inputs_are_the_products():
    rng = np.random.default_rng(0)
    for inputs in (1, 3, 4, 7, 42):
        x = rng.normal(size=(3, inputs))
        w = rng.normal(size=(inputs, 5))
        total = np.ones((3, 5))
        equations.accumulate(total, x, w)
        np.testing.assert_allclose(total, 1.0 + x @ w, rtol=1e-12, atol=1e-12)
