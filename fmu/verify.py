"""Verification of a freshly built FMU binary, before :func:`fmu.export` writes the FMU.

Three checks, all of which must pass or the export raises :class:`~fmu.errors.FMUBuildError`:

1. Exported symbols. The library's dynamic symbol table must hold exactly the fmi2
   functions that FMI 2.0 lists for the declared interfaces (:func:`fmi2_functions`), or
   for FMI 3.0 every function of ``fmi3Functions.h`` (FMI 3.0.2, section 2.5: all of them,
   whatever the interfaces), and nothing else. The table is read by :func:`elf_exported_symbols`, a small reader of
   the ELF ``.dynsym`` section, rather than by ``nm -D``: it needs no binutils (a clang or
   lld tool chain may have none, or an ``llvm-nm`` with other output), no subprocess and no
   parsing of a tool's text, and it applies exactly the dynamic loader's rules (defined,
   global or weak, default or protected visibility). ctypes alone could only confirm that
   the expected names are there, not that nothing else is. On macOS (Mach-O) ``nm -gU``
   is used instead.
2. Portability. On Linux, no symbol may need a glibc newer than
   :data:`MAX_GLIBC_VERSION` (2.17, the glibc of RHEL/CentOS 7 and of the manylinux2014
   baseline): the versions the library needs are read from its ``.gnu.version_r`` section
   (:func:`elf_required_versions`), as ``objdump -T`` shows them. glibc 2.29 gave ``pow``,
   ``log2``, ``exp`` and ``log`` new symbol versions; the templates use none of them.
3. Behaviour. In a separate Python process (:mod:`fmu.probe`, standard library only) the
   library is loaded with ctypes, and for each declared interface an instance is created
   with a logger, initialised with test states and inputs, and evaluated once: the
   derivatives and outputs (Model Exchange) or one default step and the outputs
   (Co-Simulation) must equal those computed here from the same matrices, within the
   rounding bound of a dot product; the directional derivatives (and FMI 3.0's adjoint
   derivatives) must equal the products with ``[[A, B], [C, D]]``; an FMU state saved
   before the step, restored (directly and through its serialised bytes) and stepped again
   must give bit-identical states; and a sampled FMI 3.0 FMU is also driven through its
   clock in Event Mode. A separate process, because a broken library may crash or hang the
   process that loads it (a timeout ends it), and because a library loaded into the
   exporting process could not be unloaded again.
"""

from __future__ import annotations

import json
import re
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np

from .checks import shorten
from .errors import FMUBuildError

__all__ = ["FMI2_COMMON", "FMI2_MODEL_EXCHANGE", "FMI2_CO_SIMULATION", "FMI3_FUNCTIONS",
           "MAX_GLIBC_VERSION", "fmi2_functions", "fmi_functions", "elf_exported_symbols",
           "elf_required_versions", "exported_symbols", "required_glibc", "probe_input",
           "verify_library", "PROBE_TIMEOUT"]

#: FMI 2.0.1 functions of both interfaces (section 2.1, fmi2Functions.h).
FMI2_COMMON = frozenset({
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal",
    "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger",
    "fmi2SetBoolean", "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate",
    "fmi2FreeFMUstate", "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate", "fmi2GetDirectionalDerivative"})
#: Functions of Model Exchange only (section 3.2).
FMI2_MODEL_EXCHANGE = frozenset({
    "fmi2EnterEventMode", "fmi2NewDiscreteStates", "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep", "fmi2SetTime", "fmi2SetContinuousStates",
    "fmi2GetDerivatives", "fmi2GetEventIndicators", "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates"})
#: Functions of Co-Simulation only (section 4.2).
FMI2_CO_SIMULATION = frozenset({
    "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives", "fmi2DoStep",
    "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus"})

#: Every function of FMI 3.0 (read from the shipped fmi3Functions.h, v3.0.2): an FMI 3.0
#: library must define all of them (FMI 3.0.2, section 2.5).
FMI3_FUNCTIONS = frozenset(re.findall(
    r"^FMI3_Export\s+fmi3\w+TYPE\s+(fmi3\w+);",
    (Path(__file__).with_name("c") / "fmi3" / "fmi3Functions.h").read_text(encoding="utf-8"),
    re.MULTILINE))

#: Newest glibc a Linux FMU binary may need (RHEL/CentOS 7; manylinux2014).
MAX_GLIBC_VERSION = (2, 17)

#: Longest time the behaviour check may take [s] (it takes milliseconds).
PROBE_TIMEOUT = 120.0

_SHT_DYNSYM, _SHN_UNDEF, _SHT_GNU_VERNEED = 11, 0, 0x6FFFFFFE
_STB_GLOBAL, _STB_WEAK, _STB_GNU_UNIQUE = 1, 2, 10
_STT_SECTION, _STT_FILE = 3, 4
_STV_DEFAULT, _STV_PROTECTED = 0, 3


def fmi2_functions(interfaces: tuple[str, ...]) -> frozenset[str]:
    """The fmi2 functions a library serving ``interfaces`` ("me", "cs") must export."""
    names = set(FMI2_COMMON)
    if "me" in interfaces:
        names |= FMI2_MODEL_EXCHANGE
    if "cs" in interfaces:
        names |= FMI2_CO_SIMULATION
    return frozenset(names)


def fmi_functions(fmi_version: str, interfaces: tuple[str, ...]) -> frozenset[str]:
    """The FMI functions a library of this version serving ``interfaces`` must export."""
    return fmi2_functions(interfaces) if fmi_version == "2.0" else FMI3_FUNCTIONS


def _elf_sections(data: bytes) -> tuple[str, bool, list[tuple]]:
    """Byte order, 64-bit flag and the section headers of an ELF file."""
    if data[:4] != b"\x7fELF" or len(data) < 52:
        raise ValueError("not an ELF file")
    elf_class, encoding = data[4], data[5]
    if elf_class not in (1, 2) or encoding not in (1, 2):
        raise ValueError(f"unknown ELF class {elf_class} or data encoding {encoding}")
    end = "<" if encoding == 1 else ">"
    wide = elf_class == 2
    if wide:
        shoff, = struct.unpack_from(end + "Q", data, 0x28)
        shentsize, shnum, _ = struct.unpack_from(end + "HHH", data, 0x3A)
        section = struct.Struct(end + "IIQQQQIIQQ")  # Elf64_Shdr
    else:
        shoff, = struct.unpack_from(end + "I", data, 0x20)
        shentsize, shnum, _ = struct.unpack_from(end + "HHH", data, 0x2E)
        section = struct.Struct(end + "IIIIIIIIII")  # Elf32_Shdr
    if shoff == 0 or shentsize < section.size or shoff + shnum * shentsize > len(data):
        raise ValueError("no section header table")
    return end, wide, [section.unpack_from(data, shoff + i * shentsize) for i in range(shnum)]


def elf_required_versions(data: bytes) -> dict[str, set[str]]:
    """Symbol versions an ELF shared library needs, by library (``.gnu.version_r``).

    These are the versions ``objdump -T`` shows beside undefined symbols, e.g.
    ``{"libc.so.6": {"GLIBC_2.2.5", "GLIBC_2.14"}, "libm.so.6": {"GLIBC_2.29"}}``.

    Raises
    ------
    ValueError
        If ``data`` is not an ELF file or its version section is corrupt.

    References
    ----------
    Linux Standard Base Core Specification 5.0, section 10.7.4 "Symbol Versioning"
    (Elf_Verneed, Elf_Vernaux; the same layout in 32- and 64-bit files).
    """
    end, _, headers = _elf_sections(data)
    needed: dict[str, set[str]] = {}
    verneed = struct.Struct(end + "HHIII")  # version, count, file, aux, next
    vernaux = struct.Struct(end + "IHHII")  # hash, flags, other, name, next
    for header in headers:
        if header[1] != _SHT_GNU_VERNEED:
            continue
        offset, size, link = header[4], header[5], header[6]
        if link >= len(headers) or offset + size > len(data):
            raise ValueError("corrupt version section")
        strtab = headers[link]
        strings = data[strtab[4]:strtab[4] + strtab[5]]

        def name_at(position: int) -> str:
            stop = strings.find(b"\0", position)
            return strings[position:stop if stop >= 0 else len(strings)].decode("utf-8", "replace")

        position = offset
        for _ in range(10_000):  # a bound, whatever the file says
            _, count, file_name, aux, next_entry = verneed.unpack_from(data, position)
            library = needed.setdefault(name_at(file_name), set())
            aux_position = position + aux
            for _ in range(count):
                _, _, _, name, aux_next = vernaux.unpack_from(data, aux_position)
                library.add(name_at(name))
                if aux_next == 0:
                    break
                aux_position += aux_next
            if next_entry == 0:
                break
            position += next_entry
    return needed


def required_glibc(library: Path) -> tuple[int, ...] | None:
    """Newest ``GLIBC_x.y[.z]`` version a Linux library needs, or None if it needs none."""
    newest = None
    for versions in elf_required_versions(library.read_bytes()).values():
        for version in versions:
            match = re.fullmatch(r"GLIBC_(\d+(?:\.\d+)*)", version)
            if match:
                number = tuple(int(part) for part in match.group(1).split("."))
                newest = number if newest is None or number > newest else newest
    return newest


def elf_exported_symbols(data: bytes) -> set[str]:
    """Names a dynamic loader can bind to in an ELF shared library.

    Reads the section headers, finds the ``SHT_DYNSYM`` section and its string table, and
    keeps the symbols that are defined (section index not ``SHN_UNDEF``), global, weak or
    unique, of default or protected visibility, and not section or file symbols.

    Parameters
    ----------
    data : bytes
        The whole library file.

    Raises
    ------
    ValueError
        If ``data`` is not an ELF file with a dynamic symbol table.

    References
    ----------
    System V Application Binary Interface, chapter 4 "Object Files" (ELF header, section
    header, symbol table); Tool Interface Standard ELF 1.2.
    """
    end, wide, headers = _elf_sections(data)
    shnum = len(headers)
    symbol = struct.Struct(end + ("IBBHQQ" if wide else "IIIBBH"))  # Elf64_Sym / Elf32_Sym
    # Elf*_Shdr: name, type, flags, addr, offset, size, link, info, addralign, entsize
    dynsym = [h for h in headers if h[1] == _SHT_DYNSYM]
    if not dynsym:
        raise ValueError("no dynamic symbol table")
    _, _, _, _, offset, size, link, _, _, entsize = dynsym[0]
    if link >= shnum or entsize < symbol.size or offset + size > len(data):
        raise ValueError("corrupt dynamic symbol table")
    strtab = headers[link]
    strings = data[strtab[4]:strtab[4] + strtab[5]]
    names = set()
    for position in range(offset + entsize, offset + size, entsize):  # entry 0 is null
        fields = symbol.unpack_from(data, position)
        if wide:
            name, info, other, shndx = fields[0], fields[1], fields[2], fields[3]
        else:
            name, info, other, shndx = fields[0], fields[3], fields[4], fields[5]
        binding, kind, visibility = info >> 4, info & 0xF, other & 0x3
        if (shndx == _SHN_UNDEF or binding not in (_STB_GLOBAL, _STB_WEAK, _STB_GNU_UNIQUE)
                or kind in (_STT_SECTION, _STT_FILE)
                or visibility not in (_STV_DEFAULT, _STV_PROTECTED)):
            continue
        terminator = strings.find(b"\0", name)
        text = strings[name:terminator if terminator >= 0 else len(strings)]
        if text:
            names.add(text.decode("utf-8", "replace"))
    return names


def exported_symbols(library: Path) -> set[str]:
    """Names exported by a shared library (ELF reader; ``nm -gU`` for Mach-O)."""
    data = library.read_bytes()
    if sys.platform == "darwin":
        listing = subprocess.run(["nm", "-gU", str(library)], capture_output=True, text=True,
                                 check=True).stdout
        # Mach-O C symbols carry a leading underscore
        return {line.split()[-1].removeprefix("_") for line in listing.splitlines()
                if line.strip()}
    return elf_exported_symbols(data)


def _rounding_bound(M: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Bound on |fl(M v) - fl'(M v)| for two evaluations in different orders.

    Each differs from the exact product by at most gamma_k |M| |v| with gamma_k = k u /
    (1 - k u), k the number of terms and u = eps / 2 (Higham 2002, eq. (3.5)); the two
    differ by at most twice that. k eps |M||v| is a slightly larger, simpler bound.
    """
    k = max(M.shape[1], 1)
    return 2.0 * (k + 1) * np.finfo(np.float64).eps * (np.abs(M) @ np.abs(v))


def probe_input(model, Phi: np.ndarray, Gamma: np.ndarray, step: float,
                interfaces: tuple[str, ...], library: Path, guid: str,
                fmi_version: str = "2.0") -> dict:
    """The JSON request for :mod:`fmu.probe`: test point, expected values and tolerances.

    The test point is x = u = s (1, ..., 1) with s = 1 / max(1, largest row sum of |[A B]|,
    |[C D]|, |[Phi Gamma]|), so that no product can overflow.  For a discrete-time model
    ``Phi``, ``Gamma`` are its own A, B and the probe's step is one sample period.  The
    directional derivative is probed with a seed of ones over all knowns (states and
    inputs; inputs only for a sampled model), the adjoint with ones over all unknowns
    (outputs and derivatives; outputs only for a sampled model).
    """
    n, m, p = model.n_states, model.n_inputs, model.n_outputs
    discrete = model.discrete
    if discrete:
        Phi, Gamma, step = model.A, model.B, model.sample_period
    blocks = [np.hstack([model.A, model.B]), np.hstack([model.C, model.D]),
              np.hstack([Phi, Gamma])]
    with np.errstate(over="ignore", invalid="ignore"):
        largest = max([1.0] + [float(np.max(np.sum(np.abs(b), axis=1))) for b in blocks if b.size])
    scale = 1.0 / largest if np.isfinite(largest) else 0.0
    x = np.full(n, scale)
    u = np.full(m, scale)
    xu = np.concatenate([x, u])
    ME, CS = np.hstack([model.A, model.B]), np.hstack([Phi, Gamma])
    CD = np.hstack([model.C, model.D])
    # partial derivatives: rows outputs then derivatives, columns states then inputs
    outputs_vr = list(range(m, m + p))
    states_vr = list(range(m + p, m + p + n))
    if discrete:
        jacobian = model.D
        unknowns, knowns = outputs_vr, list(range(m))
    else:
        jacobian = np.vstack([CD, ME])
        unknowns = outputs_vr + list(range(m + p + n, m + p + 2 * n))
        knowns = states_vr + list(range(m))
    ones_known, ones_unknown = np.ones(len(knowns)), np.ones(len(unknowns))
    with np.errstate(over="ignore", invalid="ignore"):
        directional = jacobian @ ones_known if jacobian.size else np.zeros(len(unknowns))
        adjoint = jacobian.T @ ones_unknown if jacobian.size else np.zeros(len(knowns))
    time_vr = m + p + n + (0 if discrete else n)
    return {
        "library": str(library), "guid": guid, "interfaces": list(interfaces),
        "fmi_version": fmi_version, "discrete": discrete, "clock_vr": time_vr + 1,
        "n_states": n, "n_inputs": m, "n_outputs": p, "step": step,
        "state_names": list(model.state_names), "output_names": list(model.output_names),
        "states": x.tolist(), "inputs": u.tolist(),
        "derivatives": (ME @ xu).tolist(), "derivatives_tolerance": _rounding_bound(ME, xu).tolist(),
        "outputs": (CD @ xu).tolist(), "outputs_tolerance": _rounding_bound(CD, xu).tolist(),
        "next_states": (CS @ xu).tolist(), "next_states_tolerance": _rounding_bound(CS, xu).tolist(),
        # outputs after the step are checked against C x1 + D u with the FMU's own x1
        "C": model.C.tolist(), "D": model.D.tolist(),
        "unknowns": unknowns, "knowns": knowns,
        "directional": directional.tolist(),
        "directional_tolerance": (_rounding_bound(jacobian, ones_known).tolist()
                                  if jacobian.size else [0.0] * len(unknowns)),
        "adjoint": adjoint.tolist(),
        "adjoint_tolerance": (_rounding_bound(jacobian.T, ones_unknown).tolist()
                              if jacobian.size else [0.0] * len(knowns)),
    }


def verify_library(library: Path, request: dict, interfaces: tuple[str, ...]) -> None:
    """Check the exported symbols, the glibc versions and the behaviour of a built library.

    Parameters
    ----------
    library : pathlib.Path
    request : dict
        From :func:`probe_input` (its ``fmi_version`` selects the FMI version).
    interfaces : tuple of {"me", "cs"}

    Raises
    ------
    FMUBuildError
        Naming what is wrong: missing or extra symbols, a symbol that needs a glibc newer
        than :data:`MAX_GLIBC_VERSION`, a library that does not load, crashes, hangs,
        refuses a call or computes other numbers.
    """
    fmi_version = request.get("fmi_version", "2.0")
    try:
        symbols = exported_symbols(library)
    except (OSError, ValueError, subprocess.CalledProcessError) as error:
        raise FMUBuildError(f"the FMU binary {library.name} cannot be read ({error}); the "
                            "build is broken. Export again; if it persists, please report it.") from error
    expected = fmi_functions(fmi_version, interfaces)
    missing, extra = sorted(expected - symbols), sorted(symbols - expected)
    if missing or extra:
        raise FMUBuildError(
            f"the FMU binary {library.name} must export exactly the {len(expected)} FMI "
            f"{fmi_version} functions of {'+'.join(interfaces)}; got {len(missing)} missing "
            f"{shorten(missing)} and {len(extra)} extra {shorten(extra)}. The build is broken: "
            "export again; if it persists, please report it.")
    if sys.platform.startswith("linux"):
        try:
            glibc = required_glibc(library)
        except (OSError, ValueError) as error:
            raise FMUBuildError(f"the FMU binary {library.name} cannot be read ({error}); the "
                                "build is broken. Export again; if it persists, please "
                                "report it.") from error
        if glibc is not None and glibc > MAX_GLIBC_VERSION:
            newest = ".".join(map(str, glibc))
            oldest = ".".join(map(str, MAX_GLIBC_VERSION))
            raise FMUBuildError(
                f"the FMU binary {library.name} needs glibc {newest}, newer than the "
                f"{oldest} every flexsat FMU may need (it would not load on older Linux "
                "systems); this compiler or C library binds a symbol the templates do not "
                "expect: please report it, with `objdump -T` of the library.")
    probe = Path(__file__).with_name("probe.py")
    command = [sys.executable, "-I", "-S", str(probe)]
    try:
        result = subprocess.run(command, input=json.dumps(request), capture_output=True,
                                text=True, errors="replace", timeout=PROBE_TIMEOUT, check=False)
    except subprocess.TimeoutExpired as error:
        raise FMUBuildError(f"the FMU binary {library.name} did not answer within "
                            f"{PROBE_TIMEOUT:.0f} s when instantiated and stepped once; the "
                            "build is broken. Please report it.") from error
    if result.returncode != 0:
        how = (f"was killed by signal {-result.returncode}" if result.returncode < 0
               else f"exited with code {result.returncode}")
        raise FMUBuildError(f"the FMU binary {library.name} failed its check: the test process "
                            f"{how}:\n{result.stderr.strip()[-2000:]}\nThe build is broken; "
                            "please report it.")
    try:
        report = json.loads(result.stdout)
    except ValueError as error:
        raise FMUBuildError(f"the FMU check printed no result ({shorten(result.stdout)}); "
                            "please report it.") from error
    if report.get("errors"):
        problems = "\n".join(f"- {e}" for e in report["errors"][:10])
        raise FMUBuildError(f"the FMU binary {library.name} failed its check:\n{problems}\n"
                            "The build is broken: export again; if it persists, please "
                            "report it.")
