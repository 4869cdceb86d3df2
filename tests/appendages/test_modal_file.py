"""The plain modal data format (appendages.modal_file): round trip, units in the file, bad files."""

from __future__ import annotations

import math

import numpy as np
import pytest

import fe_planar
from appendages import ModalAppendage
from appendages.modal_file import ModalFileError, read_modal_data, write_modal_data

SEGMENTS = [(3.0, 2.0e4, 4.0, 6), (4.0, 6.0e3, 2.0, 8)]
TIP = (5.0, 0.8, 0.3)


@pytest.fixture(scope="module")
def boom() -> ModalAppendage:
    w, G, rigid, tip = fe_planar.cantilever_modal_data(SEGMENTS, TIP)
    zeta = np.linspace(0.002, 0.01, 8)
    return ModalAppendage(w[:8], G[:8], rigid, damping=zeta, length=7.0, tip_motion=tip[:8])


def test_round_trip_is_bit_for_bit(boom, tmp_path):
    path = tmp_path / "boom.toml"
    write_modal_data(boom, path)
    again = read_modal_data(path)
    for name in ("frequencies", "participation", "rigid_mass", "damping_ratios", "tip_motion"):
        np.testing.assert_array_equal(getattr(again, name), getattr(boom, name))
    assert again.length == boom.length
    s = np.array([1.0j, 30.0 + 200.0j])
    np.testing.assert_array_equal(again.W(s), boom.W(s))


def _write(path, text):
    path.write_text(text)
    return path


FILE_IN_INCHES = """
format = "flexsat-modal-appendage"
version = 1

[units]
length = "in"
mass = "slinch"
frequency = "Hz"

[appendage]
length = {length}
damping = 0.004
frequencies = {frequencies}
rigid_mass = {rigid_mass}
participation = {participation}
"""


def test_units_in_the_file_are_converted(boom, tmp_path):
    # The same boom written in in, lbf s^2/in and Hz by hand: the reader gives back SI.
    inch, slinch = 0.0254, 0.45359237 * 9.80665 / 0.0254
    rotation = np.array([0, 1])
    G = boom.participation / (math.sqrt(slinch) * inch**rotation)
    M = boom.rigid_mass / (slinch * inch ** (rotation[:, None] + rotation[None, :]))
    text = FILE_IN_INCHES.format(length=repr(7.0 / inch),
                                 frequencies=repr((boom.frequencies / (2 * math.pi)).tolist()),
                                 rigid_mass=repr(M.tolist()), participation=repr(G.tolist()))
    read = read_modal_data(_write(tmp_path / "inches.toml", text))
    np.testing.assert_allclose(read.frequencies, boom.frequencies, rtol=1e-15)
    np.testing.assert_allclose(read.participation, boom.participation, rtol=1e-15)
    np.testing.assert_allclose(read.rigid_mass, boom.rigid_mass, rtol=1e-15)
    assert read.length == pytest.approx(7.0, rel=1e-15)
    assert np.all(read.damping_ratios == 0.004)


@pytest.mark.parametrize("change, match", [
    (("[units]", "[units]\ntime = \"s\""), r"\[units\] must give exactly.*unknown \['time'\]"),
    (('mass = "slinch"', 'mass = "pound"'), r"units\.mass unit must be one of"),
    (('frequency = "Hz"\n', ''), r"missing \['frequency'\]"),
    (("damping = 0.004", "damping = 0.004\ncolour = 3"), r"unknown key\(s\) \['colour'\]"),
    (('version = 1', 'version = 2'), r"version must be 1"),
    (("damping = 0.004", "damping = -0.004"), r"bad.toml: damping must lie in \[0, 1\)"),
])
def test_bad_files_are_refused_by_name(boom, tmp_path, change, match):
    text = FILE_IN_INCHES.format(length="275.0", frequencies=repr(boom.frequencies.tolist()),
                                 rigid_mass=repr(boom.rigid_mass.tolist()),
                                 participation=repr(boom.participation.tolist()))
    path = _write(tmp_path / "bad.toml", text.replace(*change))
    with pytest.raises(ValueError, match=match) as info:
        read_modal_data(path)
    assert "bad.toml" in str(info.value)


def test_not_toml_and_negative_mass(tmp_path):
    with pytest.raises(ModalFileError, match="not a TOML file"):
        read_modal_data(_write(tmp_path / "x.toml", "this is = = not toml"))
    text = """format = "flexsat-modal-appendage"
version = 1
[units]
length = "m"
mass = "kg"
frequency = "rad/s"
[appendage]
frequencies = [10.0]
rigid_mass = [[-2.0, 1.0], [1.0, 1.0]]
participation = [[0.5, 0.5]]
"""
    with pytest.raises(ValueError, match=r"neg.toml: rigid_mass\[0, 0\] must be positive \[kg\]"):
        read_modal_data(_write(tmp_path / "neg.toml", text))
