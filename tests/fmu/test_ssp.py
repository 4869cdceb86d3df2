"""SSP files of the digital-LQR loop: validated against the SSP 1.0 schema (fmpy's), run by
fmpy's own SSP master (FMI 2.0 FMUs) and by flexsat's master along the SSD's connections
(FMI 2.0 and 3.0), against the monolithic sampled loop.

fmpy's SSP master (fmpy.ssp.simulation.simulate_ssp) sets every component's inputs from the
connector values, steps all components, reads their outputs at the end of the step, then
copies values along the connections. So at step k the plant's torque is the controller's
output read at t_k with the controller's inputs of step k-1, while the controller's state
takes the fresh measurements - the Jacobi exchange of fmu.cosimulate - and the system input
theta_ref reaches the controller through a connection too, one step late, and from a
connector value that starts at 0. Its row k holds the values at t_k+1. The test builds that
exact loop from python-control objects.
"""

import zipfile

import control
import numpy as np
import pytest
from fmpy.ssp.ssd import read_ssd

from fmu import CosimulationError, FMUBuildError, cosimulate_ssp, write_ssp

from fmu_cases import SAMPLE_TIME, exported, lqr, loop_plant, monolithic_sampled_loop
from fmu_cases import jacobi_controller

VERSIONS = ["2.0", "3.0"]
T_END = 3.0


@pytest.fixture(scope="module")
def ssps(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ssp")
    return {v: write_ssp(folder / f"loop{v[0]}.ssp", exported("plant", v), exported("lqr", v),
                         stop_time=T_END) for v in VERSIONS}


@pytest.mark.parametrize("version", VERSIONS)
def test_ssd_validates_and_connects_by_name(ssps, version):
    structure = read_ssd(str(ssps[version]), validate=True)  # SSP 1.0 schema
    system = structure.system
    assert [e.name for e in system.elements] == ["plant", "controller"]
    assert [e.source for e in system.elements] == ["resources/plant.fmu", "resources/controller.fmu"]
    links = {(c.startElement, c.startConnector, c.endElement, c.endConnector)
             for c in system.connections}
    assert {("plant", "theta", "controller", "theta"), ("plant", "omega", "controller", "omega"),
            ("controller", "torque", "plant", "torque"),
            (None, "theta_ref", "controller", "theta_ref")} <= links
    assert {(c.name, c.kind) for c in system.connectors} == {
        ("theta_ref", "input"), ("theta", "output"), ("omega", "output"), ("torque", "output")}
    assert {u.name for u in structure.units} == {"N.m", "rad", "rad/s"}
    with zipfile.ZipFile(ssps[version]) as archive:
        assert archive.read("resources/plant.fmu") == exported("plant", version).read_bytes()


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("divisions", [1, 5])
def test_flexsat_master_runs_the_ssp(ssps, version, divisions):
    """Gauss-Seidel along the SSD's connections equals the monolithic sampled loop (1e-12
    relative, as for fmu.cosimulate)."""
    h = SAMPLE_TIME / divisions
    result = cosimulate_ssp(ssps[version], T_END, h, inputs={"theta_ref": 0.1})
    expected = monolithic_sampled_loop(T_END, h, 0.1)
    for name in ("theta", "omega", "torque"):
        np.testing.assert_allclose(result[name], expected[name], rtol=0,
                                   atol=1e-12 * np.max(np.abs(expected[name])))


def test_fmpy_runs_the_fmi2_ssp(ssps):
    """fmpy's SSP master on the FMI 2.0 SSP against the loop it computes (module
    docstring): Jacobi exchange, theta_ref delayed one step from 0, rows one step ahead."""
    from fmpy.ssp.simulation import simulate_ssp

    result = simulate_ssp(str(ssps["2.0"]), stop_time=T_END, step_size=SAMPLE_TIME,
                          input={"theta_ref": lambda t: 0.1})
    loop = control.interconnect([control.c2d(loop_plant(), SAMPLE_TIME, "zoh"),
                                 jacobi_controller(lqr())],
                                inplist=["theta_ref"], outlist=["theta", "omega", "torque"])
    n = result.size + 1
    t = np.arange(n) * SAMPLE_TIME
    delayed_reference = np.where(np.arange(n) >= 1, 0.1, 0.0)
    response = control.forced_response(loop, T=t, U=delayed_reference)
    expected = dict(zip(("theta", "omega", "torque"), np.asarray(response.outputs)))
    for name in ("theta", "omega", "torque"):
        got = result[f"loop.{name}"] if f"loop.{name}" in result.dtype.names else result[name]
        np.testing.assert_allclose(got, expected[name][1:], rtol=0,
                                   atol=1e-12 * np.max(np.abs(expected[name])))


def test_write_ssp_refuses_what_it_cannot_connect(tmp_path):
    with pytest.raises(FMUBuildError, match="connected both ways by equal signal names"):
        write_ssp(tmp_path / "x.ssp", exported("plant", "2.0"), exported("plant", "2.0"))
    with pytest.raises(FileNotFoundError, match="plant_fmu must be an existing .fmu file"):
        write_ssp(tmp_path / "x.ssp", tmp_path / "none.fmu", exported("lqr", "2.0"))
    with pytest.raises(ValueError, match=r"path must be a \.ssp file"):
        write_ssp(tmp_path / "x.zip", exported("plant", "2.0"), exported("lqr", "2.0"))
    assert not list(tmp_path.iterdir())


def test_cosimulate_ssp_refuses_a_broken_file(tmp_path, ssps):
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(ssps["2.0"]) as source, zipfile.ZipFile(broken, "w") as target:
        for item in source.namelist():
            data = source.read(item)
            if item == "SystemStructure.ssd":
                data = data.replace(b'kind="input"', b'kind="sideways"', 1)
            target.writestr(item, data)
    with pytest.raises(CosimulationError, match="cannot be read"):
        cosimulate_ssp(broken, 1.0, SAMPLE_TIME)
    with pytest.raises(FileNotFoundError, match="ssp must be an existing .ssp file"):
        cosimulate_ssp(tmp_path / "none.ssp", 1.0, SAMPLE_TIME)
