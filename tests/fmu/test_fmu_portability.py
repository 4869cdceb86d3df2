"""Portability of the FMUs: binaries that load on glibc 2.17, sources-only FMUs that an
importer compiles from sources/buildDescription.xml, the documentation folder and icon,
and state nominals from the model's scaling.
"""

import os
import re
import shutil
import struct
import subprocess
import sys
import zipfile
import zlib
from pathlib import Path
from xml.etree import ElementTree

import ctypes
import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model
from fmpy.fmi3 import FMU3Model

import fmpy
import fmpy.validation
import fmu.verify
from fmu import FMUBuildError, export
from fmu.codegen import c_double
from fmu.verify import MAX_GLIBC_VERSION, elf_required_versions

from fmu_cases import exported, hub

VERSIONS = ["2.0", "3.0"]
PLATFORM = {"2.0": "linux64", "3.0": "x86_64-linux"}
pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="the binaries checked here are Linux ELF libraries")


def library(name: str, version: str, folder: Path) -> Path:
    member = f"binaries/{PLATFORM[version]}/{name}.so"
    with zipfile.ZipFile(exported(name, version)) as archive:
        archive.extract(member, folder)
    return folder / member


# ---------------------------------------------------------------- glibc


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("name", ["hub", "lqr"])
def test_no_symbol_needs_glibc_newer_than_2_17(name, version, tmp_path):
    """``objdump -T`` lists the version each undefined symbol needs; none may be newer than
    GLIBC_2.17 (glibc 2.29 gave pow, log2, exp and log new versions). The exporter's own ELF
    reader must list the same versions."""
    objdump = shutil.which("objdump")
    if objdump is None:
        pytest.skip("objdump (binutils) is not installed: the independent listing is not possible")
    path = library(name, version, tmp_path)
    listing = subprocess.run([objdump, "-T", str(path)], capture_output=True, text=True,
                             check=True).stdout
    versions = set(re.findall(r"\(GLIBC_(\d+(?:\.\d+)+)\)", listing))
    assert versions, listing  # libc is needed: the listing must show versions
    newest = max(tuple(int(p) for p in v.split(".")) for v in versions)
    assert newest <= MAX_GLIBC_VERSION == (2, 17), listing
    ours = set().union(*elf_required_versions(path.read_bytes()).values())
    assert {f"GLIBC_{v}" for v in versions} == {v for v in ours if v.startswith("GLIBC_")}


def test_a_library_that_needs_a_newer_glibc_is_refused(tmp_path, monkeypatch):
    """Every export checks the versions: with the limit lowered below what libc's memcpy
    needs (GLIBC_2.14), the export fails with a message naming both versions."""
    monkeypatch.setattr(fmu.verify, "MAX_GLIBC_VERSION", (2, 5))
    with pytest.raises(FMUBuildError, match=r"needs glibc 2\.14, newer than the 2\.5"):
        export(hub(), tmp_path / "h.fmu")
    assert not (tmp_path / "h.fmu").exists()


def test_version_reader_sees_glibc_2_29_in_a_library_that_calls_pow(tmp_path):
    """The reader against a library built here that binds pow (GLIBC_2.29 on glibc >=
    2.29), as the templates did before they stopped using pow and log2."""
    source = tmp_path / "p.c"
    source.write_text("#include <math.h>\ndouble f(double x, double y) { return pow(x, y); }\n")
    output = tmp_path / "p.so"
    subprocess.run(["gcc", "-shared", "-fPIC", "-O2", "-fno-builtin", "-o", str(output), str(source),
                    "-lm"], check=True)
    needed = elf_required_versions(output.read_bytes())
    name, _, number = os.confstr("CS_GNU_LIBC_VERSION").partition(" ")  # "glibc 2.36"
    libc_version = tuple(int(p) for p in number.split(".")[:2])
    if name != "glibc" or libc_version < (2, 29):
        pytest.skip(f"this glibc {libc_version} predates the 2.29 pow symbol")
    assert "GLIBC_2.29" in needed["libm.so.6"]


# ---------------------------------------------------------------- sources only


def build_as_an_importer(unzipped: Path, version: str) -> Path:
    """Compile sources/ as buildDescription.xml describes, with gcc and the importer's own
    FMI headers (fmpy's copies) on the include path, into binaries/<platform>/."""
    root = ElementTree.parse(unzipped / "sources" / "buildDescription.xml").getroot()
    configuration = root.find("BuildConfiguration")
    identifier = configuration.get("modelIdentifier")
    sources = [unzipped / "sources" / f.get("name") for f in configuration.iter("SourceFile")]
    libraries = [f"-l{lib.get('name')}" for lib in configuration.iter("Library")]
    output = unzipped / "binaries" / PLATFORM[version] / f"{identifier}.so"
    output.parent.mkdir(parents=True)
    headers = Path(fmpy.__file__).parent / "c-code"
    subprocess.run(["gcc", "-shared", "-fPIC", "-std=c99", "-O2", "-pthread",
                    f"-I{unzipped / 'sources'}", f"-I{headers}", "-o", str(output),
                    *map(str, sources), *libraries], check=True, capture_output=True, text=True)
    return output


def cs_result(path_or_folder) -> np.ndarray:
    table = np.array([(0.0, 0.0), (0.5, 0.0), (0.5, 1.0)],
                     dtype=[("time", np.float64), ("torque", np.float64)])
    return simulate_fmu(str(path_or_folder), fmi_type="CoSimulation", stop_time=2.0,
                        output_interval=0.01, input=table)


@pytest.mark.slow
@pytest.mark.parametrize("version", VERSIONS)
def test_sources_only_fmu_compiles_as_its_build_description_says(version, tmp_path):
    path = export(hub(), tmp_path / "hub.fmu", fmi_version=version, sources_only=True)
    with zipfile.ZipFile(path) as archive:
        names = archive.namelist()
    assert not any(n.startswith("binaries/") for n in names)
    assert "sources/buildDescription.xml" in names
    assert fmpy.validation.validate_fmu(str(path)) == []
    unzipped = Path(extract(str(path), unzipdir=str(tmp_path / "unzipped")))
    build_as_an_importer(unzipped, version)
    # the same results as the binary FMU: same code, same operations (the optimiser may
    # contract or reorder nothing across the dot products written as plain loops)
    ours, theirs = cs_result(exported("hub", version)), cs_result(unzipped)
    for name in ("theta", "omega"):
        np.testing.assert_allclose(theirs[name], ours[name], rtol=1e-13, atol=1e-16)


@pytest.mark.slow
@pytest.mark.parametrize("version", VERSIONS)
def test_fmpy_builds_the_sources_only_fmu(version, tmp_path):
    """fmpy's own build (CMake, its FMI headers, the build configuration it reads from
    modelDescription.xml (2.0) or sources/buildDescription.xml (3.0))."""
    if shutil.which("cmake") is None:
        pytest.skip("cmake is not installed: fmpy's build_platform_binary needs it")
    from fmpy.build import build_platform_binary

    path = export(hub(), tmp_path / "hub.fmu", fmi_version=version, sources_only=True)
    unzipped = Path(extract(str(path), unzipdir=str(tmp_path / "unzipped")))
    (tmp_path / "build").mkdir()
    build_platform_binary(unzipped, build_dir=tmp_path / "build")
    assert (unzipped / "binaries" / PLATFORM[version] / "hub.so").is_file()
    ours, theirs = cs_result(exported("hub", version)), cs_result(unzipped)
    for name in ("theta", "omega"):
        np.testing.assert_allclose(theirs[name], ours[name], rtol=1e-13, atol=1e-16)


def test_sources_only_must_be_a_flag(tmp_path):
    with pytest.raises(TypeError, match="sources_only must be True or False; got str 'yes'"):
        export(hub(), tmp_path / "h.fmu", sources_only="yes")


# ---------------------------------------------------------------- documentation, icon


def read_png(data: bytes) -> tuple[int, int, np.ndarray]:
    """Width, height and RGBA pixels of a PNG written by fmu.documentation (8-bit RGBA,
    filter 0); every chunk's CRC is checked."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    position, chunks = 8, {}
    while position < len(data):
        length, = struct.unpack(">I", data[position:position + 4])
        kind = data[position + 4:position + 8]
        body = data[position + 8:position + 8 + length]
        crc, = struct.unpack(">I", data[position + 8 + length:position + 12 + length])
        assert zlib.crc32(kind + body) & 0xFFFFFFFF == crc, kind
        chunks[kind] = chunks.get(kind, b"") + body
        position += 12 + length
    width, height, depth, colour = struct.unpack(">IIBB", chunks[b"IHDR"][:10])
    assert (depth, colour) == (8, 6) and b"IEND" in chunks
    raw = zlib.decompress(chunks[b"IDAT"])
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + 4 * width)
    assert np.all(rows[:, 0] == 0)  # filter type 0 on every row
    return width, height, rows[:, 1:].reshape(height, width, 4)


@pytest.mark.parametrize("version", VERSIONS)
def test_documentation_holds_matrices_signals_units_and_nominals(version):
    with zipfile.ZipFile(exported("hub", version)) as archive:
        page = archive.read("documentation/index.html").decode()
        names = set(archive.namelist())
        licence = archive.read("documentation/licenses/license.txt").decode()
    system = hub()
    for matrix in (system.A, system.B, system.C):
        for value in np.asarray(matrix).ravel():
            assert f"<td>{c_double(value)}</td>" in page
    for signal, unit in (("torque", "N.m"), ("theta", "rad"), ("omega", "rad/s")):
        assert re.search(rf"<td class=\"name\">{signal}</td><td class=\"name\">\w+</td>"
                         rf"<td class=\"name\">{re.escape(unit)}</td>", page)
    assert "<td>5.0</td>" in page and "<td>0.011</td>" in page  # nominals of q and eta
    assert "&omega;<sub>n</sub>" in page and "<td>3</td>" in page  # the 3 rad/s mode
    assert "Redistribution and use in source and binary forms" in licence
    if version == "2.0":
        assert "documentation/_main.html" in names and "model.png" in names
    else:
        assert "documentation/diagram.png" in names


@pytest.mark.parametrize("version", VERSIONS)
def test_icon_is_a_valid_png(version):
    member = "model.png" if version == "2.0" else "documentation/diagram.png"
    for name in ("hub", "lqr"):
        with zipfile.ZipFile(exported(name, version)) as archive:
            width, height, pixels = read_png(archive.read(member))
        assert (width, height) == (96, 96)
        opaque = pixels[:, :, 3] == 255
        assert 0.2 < opaque.mean() < 0.8  # a block on a transparent background


def test_sampled_documentation_states_the_sampling():
    with zipfile.ZipFile(exported("lqr", "3.0")) as archive:
        page = archive.read("documentation/index.html").decode()
    assert "sampled every T = 0.05 s" in page and "sample_clock" in page
    assert "held until the next sample" in page


# ---------------------------------------------------------------- nominals


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.slow
def test_state_nominals_in_the_model_description_and_the_me_api(version):
    """The nominals come from the model's scaling: for the loop plant (hub J = 10 kg m^2,
    modes at 3 and 12 rad/s with participations 0.05 and 0.03) a unit torque moves the
    rigid angle by t^2 / (2 J) = 5 rad in 10 s and the modal coordinates by at most
    2 b / w^2: 0.011 and 0.00042 (two significant digits) - millimetre-like scales, not 1.0.
    fmi2/3GetNominalsOfContinuousStates returns the same values."""
    path = exported("plant", version)
    description = read_model_description(str(path))
    nominals = {v.name: float(v.nominal) for v in description.modelVariables
                if v.nominal is not None and not v.name.startswith("der(")}
    assert nominals["q"] == 5.0
    assert nominals["eta1"] == pytest.approx(2 * 0.05 / 9.0, rel=0.05)
    assert nominals["eta2"] == pytest.approx(2 * 0.03 / 144.0, rel=0.05)
    kind = FMU3Model if version == "3.0" else FMU2Model
    model = kind(guid=description.guid, unzipDirectory=extract(str(path)),
                 modelIdentifier=description.modelExchange.modelIdentifier, instanceName="n")
    model.instantiate()
    try:
        values = (ctypes.c_double * 6)()
        model.getNominalsOfContinuousStates(values, 6)
    finally:
        model.freeInstance()
    names = [v.name for v in description.modelVariables if v.name in nominals]
    assert list(values) == [nominals[n] for n in names]


@pytest.mark.slow
def test_nominals_can_be_given(tmp_path):
    path = export(hub(), tmp_path / "h.fmu", nominals=[1.0, 2.0, 1e-3, 3e-3])
    variables = {v.name: v for v in read_model_description(str(path)).modelVariables}
    assert [float(variables[s].nominal) for s in ("q", "q_dot", "eta", "eta_dot")] == \
        [1.0, 2.0, 1e-3, 3e-3]
    with pytest.raises(ValueError, match=r"nominals must be positive and finite.*got 0.0 at index 1"):
        export(hub(), tmp_path / "h.fmu", nominals=[1.0, 0.0, 1.0, 1.0])
    with pytest.raises(ValueError, match=r"nominals must have shape \(4,\)"):
        export(hub(), tmp_path / "h.fmu", nominals=[1.0])
