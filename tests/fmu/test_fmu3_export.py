"""FMI 3.0 export: validation by fmpy, modelDescription.xml, archive layout, exported
symbols, the standard's headers, and the arguments that select the version.

Systems from tests/support/fmu_cases.py (hub with one flexible mode, static PD, the digital-LQR
loop's plant and controller, a sampled double integrator), each exported once per session.
"""

import hashlib
import shutil
import subprocess
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import control
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

import fmpy
from fmu import FMUBuildError, export
from fmu.codegen import template_dir
from fmu.verify import FMI3_FUNCTIONS

from fmu_cases import exported, hub

NAMES = ["hub", "pd", "plant", "lqr", "sampled"]


@pytest.mark.slow
@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", NAMES)
def test_validate_fmu_finds_no_problems(name, version):
    """fmpy's validation: schema, variable names, ModelStructure, start values,
    causality/variability combinations, units; FMI 3.0 also one independent variable and
    unique value references."""
    assert validate_fmu(str(exported(name, version))) == []


def test_model_description_3():
    description = read_model_description(str(exported("hub", "3.0")))
    assert description.fmiVersion == "3.0"
    variables = {v.name: v for v in description.modelVariables}
    # value references: inputs, outputs, states, derivatives, then time (lti_instance.h)
    assert [(v.name, v.valueReference) for v in description.modelVariables] == [
        ("time", 11), ("torque", 0), ("theta", 1), ("omega", 2), ("q", 3), ("q_dot", 4),
        ("eta", 5), ("eta_dot", 6), ("der(q)", 7), ("der(q_dot)", 8), ("der(eta)", 9),
        ("der(eta_dot)", 10)]
    assert variables["time"].causality == "independent" and variables["time"].unit == "s"
    assert all(v.type == "Float64" for v in description.modelVariables)
    assert variables["torque"].unit == "N.m" and variables["theta"].unit == "rad"
    assert variables["der(q_dot)"].derivative is variables["q_dot"]
    assert variables["q"].unit is None  # "q" names no physical quantity (fmu.units)
    # nominals from the unit-torque step over the 10 s default experiment (fmu.system):
    # q = t^2 / (2 J) reaches 5 rad, eta = 0.05 (1 - cos 3t) / 9 at most 0.011 rad
    assert float(variables["q"].nominal) == 5.0
    assert float(variables["eta"].nominal) == pytest.approx(0.011, abs=0)
    # capabilities, read from the XML (fmpy maps only some FMI 3.0 attribute names)
    root = ElementTree.fromstring(zipfile.ZipFile(exported("hub", "3.0")).read("modelDescription.xml"))
    for element in ("ModelExchange", "CoSimulation"):
        attributes = root.find(element).attrib
        for capability in ("canGetAndSetFMUState", "canSerializeFMUState",
                           "providesDirectionalDerivatives", "providesAdjointDerivatives"):
            assert attributes[capability] == "true", (element, capability)
    assert root.find("CoSimulation").get("canHandleVariableCommunicationStepSize") == "true"
    assert root.find("CoSimulation").get("hasEventMode") == "false"
    assert root.find("ModelExchange").get("needsCompletedIntegratorStep") == "false"
    outputs = {u.variable.name: sorted(d.name for d in u.dependencies) for u in description.outputs}
    assert outputs == {"theta": ["eta", "q"], "omega": ["eta_dot", "q_dot"]}  # from C
    derivatives = {u.variable.name: sorted(d.name for d in u.dependencies)
                   for u in description.derivatives}
    assert derivatives["der(q_dot)"] == ["torque"]  # B only: the rigid body
    assert derivatives["der(eta_dot)"] == ["eta", "eta_dot", "torque"]


def test_sampled_model_description_3():
    """A sampled system: CS only with Event Mode, a periodic input clock of interval T, the
    outputs clocked by it, discrete states; no derivatives."""
    description = read_model_description(str(exported("lqr", "3.0")))
    assert description.modelExchange is None and description.coSimulation.hasEventMode
    variables = {v.name: v for v in description.modelVariables}
    clock = variables["sample_clock"]
    assert clock.type == "Clock" and clock.causality == "input"
    assert clock.intervalVariability == "constant"
    with zipfile.ZipFile(exported("lqr", "3.0")) as archive:
        text = archive.read("modelDescription.xml").decode()
    assert 'intervalDecimal="0.05"' in text and 'fixedInternalStepSize="0.05"' in text
    assert [c.name for c in variables["torque"].clocks] == ["sample_clock"]
    assert variables["torque"].variability == "discrete"
    assert variables["xhat0"].variability == "discrete" and variables["xhat0"].causality == "local"
    assert not any(name.startswith("der(") for name in variables)
    # D = [g, 0, 0]: the torque feeds through from theta_ref only (and ticks with the clock)
    (output,) = description.outputs
    assert sorted(d.name for d in output.dependencies) == ["sample_clock", "theta_ref"]


def test_archive_layout_3():
    with zipfile.ZipFile(exported("hub", "3.0")) as archive:
        names = set(archive.namelist())
    assert {"modelDescription.xml", "binaries/x86_64-linux/hub.so", "sources/model.c",
            "sources/fmi3Functions.c", "sources/lti_instance.c", "sources/linear_model.c",
            "sources/linear_model.h", "sources/lti_instance.h", "sources/flexsat_interfaces.h",
            "sources/buildDescription.xml", "documentation/index.html",
            "documentation/diagram.png", "documentation/licenses/license.txt"} <= names
    # FMI 3.0.2, section 2.5.1.4: the standard's headers come from the importer
    assert not any(Path(n).name.startswith("fmi3") and n.endswith(".h") for n in names)
    assert not any(Path(n).name.startswith("fmi2") for n in names)


def test_binary_defines_every_fmi3_function_and_nothing_else(tmp_path):
    """FMI 3.0.2, section 2.5: all functions of fmi3Functions.h, whatever the interfaces
    (75 in v3.0.2). Listed with nm, independently of the exporter's own ELF reader."""
    nm = shutil.which("nm")
    assert nm is not None, "nm not found although gcc built the FMU (binutils missing?)"
    for name in ("hub", "lqr"):
        with zipfile.ZipFile(exported(name, "3.0")) as archive:
            archive.extract(f"binaries/x86_64-linux/{name}.so", tmp_path)
        listing = subprocess.run([nm, "-D", "--defined-only",
                                  str(tmp_path / f"binaries/x86_64-linux/{name}.so")],
                                 capture_output=True, text=True, check=True).stdout
        symbols = {line.split()[-1] for line in listing.splitlines() if line.strip()}
        assert symbols == set(FMI3_FUNCTIONS)
    assert len(FMI3_FUNCTIONS) == 75


# SHA-256 of headers/<name> at tag v3.0.2 of github.com/modelica/fmi-standard (LF, as
# published) and at tag v3.0.1 (its CRLF line endings turned into LF).
FMI_3_0_2_HEADERS = {
    "fmi3Functions.h": "038358fb0209c3547fe8c6f03b80582960c93ce0a7d342b0d9348c8ce6137784",
    "fmi3FunctionTypes.h": "d247d1c5fbf58e32379f1d38e7f73990709e0501fc4a9b3901ce3f9638503a0f",
    "fmi3PlatformTypes.h": "1aa81efddeb84b0d9425f9226969525bd034cb63848c086b6696655179500616",
}
FMI_3_0_1_HEADERS = {
    "fmi3Functions.h": "6367e9f7895848ed8d06c8a9b7f77e72d9f3eae102f64c313d51c10049b720ee",
    "fmi3FunctionTypes.h": "77bb086dbf9b9123f75edc2a90a0f27fb5c32f913ab3f9b69fe2e2cbc2448b24",
    "fmi3PlatformTypes.h": "19ea19ae07cdab582931fc1a545d9aeef3d5066da131ee96a7e393e72164fa30",
}


def _sha256_lf(path: Path) -> str:
    return hashlib.sha256(path.read_bytes().replace(b"\r\n", b"\n")).hexdigest()


@pytest.mark.parametrize("name", sorted(FMI_3_0_2_HEADERS))
def test_fmi3_headers_are_the_published_ones(name):
    assert _sha256_lf(template_dir() / "fmi3" / name) == FMI_3_0_2_HEADERS[name]
    licence = (template_dir() / "fmi3" / "LICENSE.txt").read_text()
    assert FMI_3_0_2_HEADERS[name] in licence and "2-Clause BSD License" in licence


@pytest.mark.parametrize("name", sorted(FMI_3_0_1_HEADERS))
def test_fmpys_fmi3_headers_are_the_published_v3_0_1(name):
    """The headers fmpy ships (and compiles sources-only FMUs with) are the standard's
    v3.0.1, verbatim; v3.0.2 differs only in copyright years and two (void) prototypes."""
    header = Path(fmpy.__file__).parent / "c-code" / name
    if not header.is_file():
        pytest.skip(f"this fmpy ships no {name}")
    assert _sha256_lf(header) == FMI_3_0_1_HEADERS[name]


def test_version_argument(tmp_path):
    with pytest.raises(ValueError, match=r'fmi_version must be "2.0" or "3.0"; got \'2\''):
        export(hub(), tmp_path / "h.fmu", fmi_version="2")
    with pytest.raises(TypeError, match=r"fmi_version must be a str.*got float 3.0"):
        export(hub(), tmp_path / "h.fmu", fmi_version=3.0)


def test_reserved_names_in_fmi3(tmp_path):
    """FMI 3.0 adds the variable 'time' (and 'sample_clock'): a signal of that name would
    make two variables of one name. FMI 2.0 has neither."""
    clocked = control.ss([[0.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=["time"], states=["x"])
    with pytest.raises(FMUBuildError, match=r"signal name 'time' is used by the FMI 3.0 FMU itself"):
        export(clocked, tmp_path / "t.fmu", fmi_version="3.0")
    assert validate_fmu(str(export(clocked, tmp_path / "t2.fmu", fmi_version="2.0"))) == []


def test_guids_differ_between_versions():
    guids = {read_model_description(str(exported("hub", v))).guid for v in ("2.0", "3.0")}
    assert len(guids) == 2


def test_same_model_code_in_both_versions():
    """One exporter, not a fork: the model code of both FMUs is byte for byte the same;
    only the API layer differs."""
    files = {}
    for version in ("2.0", "3.0"):
        with zipfile.ZipFile(exported("hub", version)) as archive:
            files[version] = {n: archive.read(n) for n in archive.namelist()
                              if n in ("sources/lti_instance.c", "sources/linear_model.c",
                                       "sources/linear_model.h", "sources/lti_instance.h")}
    assert len(files["2.0"]) == 4 and files["2.0"] == files["3.0"]
    # model.c differs only in the GUID
    texts = []
    for version in ("2.0", "3.0"):
        with zipfile.ZipFile(exported("hub", version)) as archive:
            texts.append(archive.read("sources/model.c").decode())
    differing = [(a, b) for a, b in zip(*(t.splitlines() for t in texts)) if a != b]
    assert len(differing) == 1 and "{" in differing[0][0]
