"""A NumPy integer (``np.int64(10)``, as ``len`` and indexing of arrays give) is an integer wherever
Python's ``10`` is: sweep specs, family settings and fields, saved designs, solver settings."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks.core.sweep_spec import expand, parse_sweep
from rmpc.io.design import Design
from rmpc.io.format import FORMAT, VERSION, read_file
from rmpc.qp.osqp_backend import OSQPSettings
from toolkit_common.errors import ConfigError, InvalidArgumentError


def test_a_sweep_takes_numpy_integers_for_its_counts_and_integer_settings():
    spec = parse_sweep({
        "max_cases": np.int64(10),
        "base": {"controller": "GIPC", "settings": {"Np": np.int64(100), "Nc": np.int32(3)}},
        "montecarlo": {"n": np.int64(2), "seed": np.int64(7)},
    })
    cases = expand(spec)
    assert len(cases) == 2
    assert cases[0].settings["Np"] == 100 and type(cases[0].settings["Np"]) is int
    assert spec.montecarlo == {"n": 2, "seed": 7} and type(spec.montecarlo["n"]) is int
    # the same values as floats or bools are still refused
    with pytest.raises(ConfigError, match=r"montecarlo\.n"):
        parse_sweep({"base": {"controller": "GIPC"}, "montecarlo": {"n": np.float64(2.0)}})
    with pytest.raises(ConfigError, match="max_cases"):
        parse_sweep({"max_cases": np.bool_(True), "base": {"controller": "GIPC"}})


def test_a_family_number_setting_takes_a_numpy_integer():
    spec = parse_sweep({"base": {"controller": "GIPC", "settings": {"R_du": np.int64(2)}}})
    assert expand(spec)[0].settings["R_du"] == 2.0


def test_the_wheel_family_takes_numpy_integers_for_wheel_and_seed():
    spec = parse_sweep({"base": {"family": "wheel", "fault_wheel": np.int64(3), "seed": np.int64(4)}})
    case = expand(spec)[0]
    assert case.fault_wheel == 3 and case.seed == 4 and type(case.fault_wheel) is int
    with pytest.raises(ConfigError, match="fault_wheel"):
        parse_sweep({"base": {"family": "wheel", "fault_wheel": np.int64(5)}})


def test_a_saved_design_reads_a_numpy_integer_as_an_integer():
    design = Design({"N": np.int64(10), "x": np.int64(3)})
    assert design.integer("N") == 10 and design.number("x") == 3.0
    with pytest.raises(InvalidArgumentError, match=r"design\.N"):
        Design({"N": np.float64(10.0)}).integer("N")


def test_a_controller_file_version_may_not_be_a_float(tmp_path):
    # a JSON file gives Python ints; the version check is the shared one (a float stays refused)
    path = tmp_path / "c.json"
    path.write_text(json.dumps({"format": FORMAT, "version": float(VERSION)}))
    with pytest.raises(InvalidArgumentError, match="version"):
        read_file(path)


def test_osqp_settings_take_a_numpy_integer_scaling():
    assert OSQPSettings(scaling=np.int64(10)).scaling == 10
    with pytest.raises(InvalidArgumentError, match="scaling"):
        OSQPSettings(scaling=np.float64(10.0))
