"""clsamp samplers as scipy.stats.qmc engines (as_qmc_engine); scipy.stats imported on first use."""

import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.stats import qmc

import clsamp
from clsamp.errors import InvalidArgumentError


def test_a_sequence_engine_walks_one_realization():
    sampler = clsamp.make_sampler("sobol:owen", d=3, seed=5)
    engine = clsamp.as_qmc_engine(sampler, realization=2)
    assert isinstance(engine, qmc.QMCEngine) and engine.d == 3
    whole = sampler.sample(128, realizations=range(2, 3))[0]
    first, second = engine.random(64), engine.random(64)
    assert np.array_equal(np.concatenate([first, second]), whole)
    assert engine.num_generated == 128
    engine.reset()
    assert np.array_equal(engine.random(64), first)
    engine.reset().fast_forward(100)
    assert np.array_equal(engine.random(28), whole[100:])
    assert engine.random(0).shape == (0, 3)


def test_a_set_engine_draws_a_fresh_set_each_call():
    sampler = clsamp.make_sampler("jittered", d=2, seed=4)
    engine = clsamp.as_qmc_engine(sampler)
    sets = sampler.sample(16, realizations=3)
    assert np.array_equal(engine.random(16), sets[0])
    assert np.array_equal(engine.random(16), sets[1])
    engine.reset()
    assert np.array_equal(engine.random(16), sets[0])
    engine.fast_forward(16)                                # skips one set
    assert np.array_equal(engine.random(16), sets[2])
    with pytest.raises(InvalidArgumentError, match="nearest valid n is 16"):
        engine.random(15)


def test_scipy_tools_take_the_engine():
    engine = clsamp.as_qmc_engine(clsamp.make_sampler("halton", d=2))
    x = engine.random(50)
    scaled = qmc.scale(x, [-1, 0], [1, 10])
    assert scaled.shape == (50, 2) and scaled[:, 1].max() <= 10
    assert np.allclose(x, qmc.Halton(2, scramble=False).random(50), rtol=0, atol=1e-15)
    assert qmc.discrepancy(x) < qmc.discrepancy(np.random.default_rng(0).random((50, 2)))


def test_bad_input_and_import_clsamp_leaves_scipy_out():
    with pytest.raises(InvalidArgumentError, match="'sampler'"):
        clsamp.as_qmc_engine("sobol")
    with pytest.raises(InvalidArgumentError, match="'realization'"):
        clsamp.as_qmc_engine(clsamp.make_sampler("random"), realization=-1)
    code = "import sys, clsamp; print('scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=os.path.dirname(os.path.dirname(__file__)))
    assert out.stdout.strip() == "False"
