"""fmu.export and fmu.cosimulate at their boundary: every argument checked by type and
value with a message that names it, work estimated and refused before it starts, names and
text that C and XML can hold, UTF-8 output whatever the locale, and an FMU file that is
written all or nothing, never through a planted symlink.
"""

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import read_model_description

import fmu
import fmu.limits
from fmu import FMUBuildError, cosimulate, export

ROOT = Path(__file__).resolve().parents[2]


def body(name="body"):
    """J theta'' = torque with J = 10 kg m^2; outputs theta, omega."""
    return control.ss([[0, 1], [0, 0]], [[0], [0.1]], np.eye(2), 0, inputs=["torque"],
                      outputs=["theta", "omega"], states=["angle", "rate"], name=name)


# ---------------------------------------------------------------- types and values


@pytest.mark.parametrize("kwargs, message", [
    ({"description": 3}, r"description must be a str; got int 3"),
    ({"model_name": 3}, r"model_name must be a str \(a C identifier\); got int 3"),
    ({"interfaces": 3}, r"interfaces must be 'me', 'cs' or a sequence of them; got int 3"),
    ({"step": "0.1"}, r"step must be a real number \[s\]; got str '0.1'"),
    ({"stop_time": None}, r"stop_time must be a real number \[s\]; got NoneType None"),
    ({"step": True}, r"step must be a real number \[s\]; got bool True"),
    ({"reference": "yes"}, r"reference must be True or False; got str 'yes'"),
    ({"compiler": 3}, r"compiler must be a str or os.PathLike \(the C compiler\); got int 3"),
    ({"x0": "ab"}, r"x0 must be an array of 2 real numbers .*; got str 'ab'"),
    ({"x0": {"angle": 1.0}}, r"x0 must be an array of 2 real numbers"),
    ({"units": [("theta", "rad")]}, r"units must be a mapping \{signal name: unit\}; got list"),
    ({"max_reference_samples": "many"}, r"max_reference_samples must be a real number"),
])
def test_wrong_types_are_type_errors_naming_the_argument(tmp_path, kwargs, message):
    with pytest.raises(TypeError, match=message):
        export(body(), tmp_path / "b.fmu", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_path_of_the_wrong_type(tmp_path):
    with pytest.raises(TypeError, match=r"path must be a str or os.PathLike .*; got int 3"):
        export(body(), 3)


@pytest.mark.parametrize("kwargs, message", [
    ({"interfaces": ["me", 3]}, r"interfaces must be a non-empty selection of 'me' and 'cs'; got \('me', 3\)"),
    ({"interfaces": ()}, r"interfaces must be a non-empty selection"),
    ({"max_reference_samples": 0}, r"max_reference_samples must be at least 1; got 0"),
    ({"units": {7: "rad"}}, r"units names the signal 7, which the system does not have"),
    ({"units": {"theta": ["rad"]}}, r"units\['theta'\] must be one of .*; got \['rad'\]"),
])
def test_bad_values_are_value_errors_naming_the_argument(tmp_path, kwargs, message):
    with pytest.raises(ValueError, match=message):
        export(body(), tmp_path / "b.fmu", **kwargs)


# ---------------------------------------------------------------- names for C and XML


@pytest.mark.parametrize("name", ["body\n", "body\r\n", "bo dy", "body;", "\nbody"])
def test_model_name_is_matched_whole(tmp_path, name):
    """'^...$' accepts "body\\n" ($ matches before a final newline); the name then breaks
    the generated C. It must be refused up front, by name."""
    with pytest.raises(ValueError, match="model_name must be a C identifier"):
        export(body(), tmp_path / "b.fmu", model_name=name)


@pytest.mark.parametrize("name", ["theta\n", "theta\r", "x[0]\n", "x\n[0]"])
def test_signal_names_are_matched_whole(tmp_path, name):
    system = control.ss([[0.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=[name], states=["x"])
    with pytest.raises(FMUBuildError, match="output name .* is not a legal FMI variable name"):
        export(system, tmp_path / "b.fmu")


@pytest.mark.parametrize("text, code, position", [
    ("speed\x01up", "U+0001", 5), ("\x1b[31mred", "U+001B", 0), ("a\x00b", "U+0000", 1),
    ("bad \ud800 half", "U+D800", 4), ("no \uffff", "U+FFFF", 3)])
def test_xml_illegal_characters_in_description_are_refused(tmp_path, text, code, position):
    with pytest.raises(ValueError, match=rf"description must be text that XML 1.0 can hold .*; "
                                         rf"got {re.escape(code)} at position {position} of"):
        export(body(), tmp_path / "b.fmu", description=text)
    assert list(tmp_path.iterdir()) == []


def test_xml_illegal_characters_in_the_system_name_are_refused(tmp_path):
    """The default description quotes the system's name; the path gives the identifier."""
    with pytest.raises(ValueError, match=r"system.name \(part of the default description\) must "
                                         r"be text that XML 1.0 can hold .*U\+0007 at position 4"):
        export(body("body\x07"), tmp_path / "b.fmu")


def test_a_description_or_model_name_over_its_limit_is_refused_before_any_work(tmp_path):
    """Issue-9 review: a 200,000-character description was accepted (and written into
    modelDescription.xml); a 100,000-character model_name reached gcc, which failed on the
    file name ("a bug in flexsat.fmu"). Both are refused by name with their documented limits
    (fmu.limits), before any file is written; the limit itself is accepted."""
    with pytest.raises(ValueError, match=r"description must have at most "
                                         r"fmu\.limits\.MAX_DESCRIPTION_LENGTH = 4096 "
                                         r"characters; got 200000 \('xxxx"):
        export(body(), tmp_path / "b.fmu", description="x" * 200_000)
    with pytest.raises(ValueError, match=r"model_name must have at most "
                                         r"fmu\.limits\.MAX_MODEL_NAME_LENGTH = 200 "
                                         r"characters; got 100000"):
        export(body(), tmp_path / "b.fmu", model_name="a" * 100_000)
    assert list(tmp_path.iterdir()) == []
    text = "y" * fmu.limits.MAX_DESCRIPTION_LENGTH
    name = "m" * fmu.limits.MAX_MODEL_NAME_LENGTH
    path = export(body(), tmp_path / "b.fmu", description=text, model_name=name,
                  sources_only=True)
    assert read_model_description(str(path)).description == text


@pytest.mark.slow
def test_a_compiler_that_cannot_compile_anything_is_named_not_called_a_bug(tmp_path):
    """A compiler that fails a trivial C file (here /bin/false) is an environment error,
    FMUCompilerError, one line naming it; one that compiles a trivial file but fails on our
    model.c stays a build error that says it is ours to fix (with the compiler's output)."""
    with pytest.raises(fmu.FMUCompilerError, match=r"^the C compiler /bin/false \(passed as "
                                                   r"compiler=\) does not work: [^\n]*$"):
        export(body(), tmp_path / "b.fmu", compiler="/bin/false")
    picky = tmp_path / "picky-cc"
    picky.write_text('#!/bin/sh\ncase "$*" in *model.c*) echo "model.c:1: error: boom" >&2; '
                     'exit 1;; esac\nexec gcc "$@"\n')
    picky.chmod(0o755)
    with pytest.raises(FMUBuildError, match=r"(?s)model\.c:1: error: boom.*This is a bug in "
                                            r"flexsat\.fmu") as error:
        export(body(), tmp_path / "b.fmu", compiler=str(picky))
    assert not isinstance(error.value, fmu.FMUCompilerError)
    assert not (tmp_path / "b.fmu").exists()


def test_tab_newline_and_unicode_are_fine_in_a_description(tmp_path):
    text = "Nutzlast\twith a\nnew line and ΔT → 😀"
    description = read_model_description(str(export(body(), tmp_path / "b.fmu", description=text)))
    # written as character references (&#9; &#10;), which attribute-value normalisation keeps
    assert description.description == text


def test_messages_are_truncated(tmp_path):
    long_name = "a" * 500 + "-"
    system = control.ss([[0.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=[long_name], states=["x"])
    with pytest.raises(FMUBuildError) as error:
        export(system, tmp_path / "b.fmu")
    assert "..." in str(error.value) and len(str(error.value)) < 500
    with pytest.raises(ValueError) as error:
        export(body(), tmp_path / "b.fmu", description="x" * 10**6 + "\x01")
    assert len(str(error.value)) < 400
    with pytest.raises(ValueError) as error:
        export(body(), tmp_path / "b.fmu", x0=np.zeros(200_000))
    assert len(str(error.value)) < 200


# ---------------------------------------------------------------- limits


def test_huge_reference_is_refused_before_any_work(tmp_path):
    """stop_time / step = 1e12 samples would need terabytes: refused at once."""
    with pytest.raises(ValueError, match=r"reference files for stop_time / step = 1000000000.0 s / "
                                         r"0.001 s need 1e\+12 samples \(about .* TiB of memory "
                                         r"and .* TiB of CSV\); expected at most "
                                         r"max_reference_samples = 1e\+06"):
        export(body(), tmp_path / "b.fmu", stop_time=1e9, step=1e-3, reference=True)
    assert list(tmp_path.iterdir()) == []
    # without reference files the same stop time is only a number in the description
    export(body(), tmp_path / "b.fmu", stop_time=1e9, step=1e-3)


def test_reference_limit_can_be_raised_by_keyword(tmp_path):
    # stop_time / step = 2 / 0.001: 2001 samples
    with pytest.raises(ValueError, match=r"2001 samples .* max_reference_samples = 2000"):
        export(body(), tmp_path / "b.fmu", stop_time=2.0, step=1e-3, reference=True,
               max_reference_samples=2000)
    export(body(), tmp_path / "b.fmu", stop_time=2.0, step=1e-3, reference=True,
           max_reference_samples=2001)
    assert len((tmp_path / "b_ref.csv").read_text(encoding="utf-8").splitlines()) == 1 + 2001 + 1


def test_reference_memory_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(fmu.limits, "MAX_REFERENCE_MEMORY", 2**20)
    with pytest.raises(ValueError, match=r"expected at most fmu.limits.MAX_REFERENCE_MEMORY = 1 MiB"):
        export(body(), tmp_path / "b.fmu", stop_time=100.0, step=1e-3, reference=True)


def test_number_of_states_and_signals_is_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr(fmu.limits, "MAX_STATES", 1)
    with pytest.raises(ValueError, match=r"at most fmu.limits.MAX_STATES = 1 states; got 2"):
        export(body(), tmp_path / "b.fmu")
    monkeypatch.setattr(fmu.limits, "MAX_STATES", 2)
    monkeypatch.setattr(fmu.limits, "MAX_SIGNALS", 2)
    with pytest.raises(ValueError, match=r"at most fmu.limits.MAX_SIGNALS = 2 inputs plus outputs; "
                                         r"got 1 \+ 2"):
        export(body(), tmp_path / "b.fmu")
    monkeypatch.setattr(fmu.limits, "MAX_SIGNALS", 3)
    assert export(body(), tmp_path / "b.fmu").is_file()


def test_cosimulation_steps_are_bounded():
    with pytest.raises(ValueError, match=r"at most fmu.limits.MAX_COSIMULATION_STEPS = 1e\+07 steps "
                                         r"of 0.001 s; got 1000000000.0 s = 1e\+12 steps"):
        cosimulate("plant.fmu", "controller.fmu", 1e9, 1e-3)


# ---------------------------------------------------------------- files


NON_UTF8_LOCALE = """
import sys, locale
sys.path.insert(0, {root!r})
assert locale.getpreferredencoding(False) in ("ANSI_X3.4-1968", "US-ASCII", "ascii"), locale.getpreferredencoding(False)
import control, numpy as np
from fmu import export
body = control.ss([[0, 1], [0, 0]], [[0], [0.1]], np.eye(2), 0, inputs=["torque"],
                  outputs=["theta", "omega"], states=["angle", "rate"])
export(body, {target!r}, description={text}, reference=True, stop_time=0.1)
"""


@pytest.mark.slow
def test_files_are_utf8_in_an_ascii_locale(tmp_path):
    """LC_ALL=C without Python's C-locale coercion and UTF-8 mode: the locale's encoding is
    ASCII. modelDescription.xml declares UTF-8 and must be UTF-8."""
    text = "Nutzlast – ΔT Wärme"
    target = tmp_path / "body.fmu"
    environment = {**{k: v for k, v in os.environ.items() if not k.startswith(("LC_", "LANG"))},
                   "LC_ALL": "C", "PYTHONCOERCECLOCALE": "0", "PYTHONUTF8": "0"}
    script = tmp_path / "export_in_c_locale.py"  # ASCII only: the locale cannot decode more
    script.write_text(NON_UTF8_LOCALE.format(root=str(ROOT), target=str(target), text=ascii(text)))
    result = subprocess.run([sys.executable, str(script)], env=environment, capture_output=True,
                            text=True, encoding="utf-8", errors="replace")
    assert result.returncode == 0, result.stderr[-2000:]
    assert read_model_description(str(target)).description == text
    import zipfile
    with zipfile.ZipFile(target) as archive:
        assert text in archive.read("modelDescription.xml").decode("utf-8")
    for name in ("body_in.csv", "body_ref.csv", "body_ref.opt"):
        (tmp_path / name).read_bytes().decode("utf-8")


def test_a_planted_symlink_is_not_followed(tmp_path):
    """The old exporter wrote <target>.partial, following a symlink of that name."""
    victim = tmp_path / "precious.txt"
    victim.write_text("do not overwrite")
    (tmp_path / "b.fmu.partial").symlink_to(victim)
    path = export(body(), tmp_path / "b.fmu")
    assert victim.read_text() == "do not overwrite"
    assert path.is_file() and not path.is_symlink()


def test_a_symlink_at_the_target_is_replaced_not_followed(tmp_path):
    victim = tmp_path / "precious.txt"
    victim.write_text("do not overwrite")
    (tmp_path / "b.fmu").symlink_to(victim)
    (tmp_path / "b_ref.csv").symlink_to(victim)
    export(body(), tmp_path / "b.fmu", reference=True, stop_time=0.1)
    assert victim.read_text() == "do not overwrite"
    assert not (tmp_path / "b.fmu").is_symlink() and not (tmp_path / "b_ref.csv").is_symlink()
    assert read_model_description(str(tmp_path / "b.fmu")).modelName == "b"


@pytest.mark.slow
def test_failed_export_leaves_nothing(tmp_path):
    """A compiler that fails: no FMU, no temporary file, and an existing FMU is kept."""
    cc = tmp_path / "bad-cc"
    cc.write_text(textwrap.dedent("""\
        #!/bin/sh
        case "$*" in *model.c*) echo "model.c: error: no" >&2; exit 1;; esac
        exec gcc "$@"
    """))
    cc.chmod(0o755)
    out = tmp_path / "out"
    out.mkdir()
    (out / "b.fmu").write_bytes(b"the previous FMU")
    with pytest.raises(FMUBuildError, match="compiling the FMU binary failed"):
        export(body(), out / "b.fmu", compiler=cc)
    assert sorted(p.name for p in out.iterdir()) == ["b.fmu"]
    assert (out / "b.fmu").read_bytes() == b"the previous FMU"
