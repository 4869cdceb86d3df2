"""The FMU sources of both FMI versions under AddressSanitizer and UndefinedBehaviorSanitizer,
and the FMI 3.0 sources under ThreadSanitizer (instances of one FMU in four threads).

A C harness per version, compiled with an FMU's sources (as a source-code importer would),
drives every new code path - steps of the default size, of other sizes, long sampled steps
(binary powering), FMU states saved, serialised, deserialised and restored, directional and
adjoint derivatives, the sample clock in Event Mode, Model Exchange - and must finish with
no sanitizer report. ``-fno-sanitize-recover=all`` turns any report into a failing exit.
"""

import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

import fmpy

from fmu_cases import SAMPLE_TIME, exported

FLAGS = ["-std=c99", "-g", "-O1", "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
         "-fno-omit-frame-pointer"]

HARNESS3 = r"""
#include <stdio.h>
#include <string.h>
#include "fmi3Functions.h"

static int errors = 0;
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m)
{
    (void)e; (void)c;
    if (s >= fmi3Error) { errors++; printf("log: %s\n", m); }
}

#define CHECK(call) do { if ((call) > fmi3Discard) { printf("failed: %s\n", #call); return 1; } } while (0)

static int exercise(fmi3Instance fmu, int event_mode)
{
    fmi3ValueReference vr[N_VR], unknowns[N_UNKNOWNS], knowns[N_KNOWNS];
    fmi3Float64 values[N_VR], seed[N_VR], sensitivity[N_VR];
    for (int i = 0; i < N_VR; i++) { vr[i] = (fmi3ValueReference)i; seed[i] = 1.0 + i; }
    for (int i = 0; i < N_UNKNOWNS; i++) unknowns[i] = FIRST_UNKNOWN[i];
    for (int i = 0; i < N_KNOWNS; i++) knowns[i] = FIRST_KNOWN[i];
    CHECK(fmi3EnterInitializationMode(fmu, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    for (int k = 0; k < N_INPUTS; k++) values[k] = 0.1 * (k + 1);
    CHECK(fmi3SetFloat64(fmu, vr, N_INPUTS, values, N_INPUTS));
    CHECK(fmi3ExitInitializationMode(fmu));
    if (event_mode) {
        const fmi3ValueReference clock = CLOCK_VR;
        const fmi3Clock active = fmi3ClockActive;
        fmi3Boolean a, b, c, d, e;
        fmi3Float64 next;
        CHECK(fmi3SetClock(fmu, &clock, 1, &active));
        CHECK(fmi3GetFloat64(fmu, vr, N_VR, values, N_VR));
        CHECK(fmi3UpdateDiscreteStates(fmu, &a, &b, &c, &d, &e, &next));
        CHECK(fmi3EnterStepMode(fmu));
    }
    fmi3FMUState state = NULL, copy = NULL;
    CHECK(fmi3GetFMUState(fmu, &state));
    const double steps[] = {STEP, 0.037, 2.5 * STEP, 1000.5 * STEP, 5.0, 1e-6};
    double t = 0.0;
    for (int round = 0; round < 2; round++) {
        for (size_t j = 0; j < sizeof steps / sizeof steps[0]; j++) {
            fmi3Boolean event, terminate, early;
            fmi3Float64 last;
            CHECK(fmi3DoStep(fmu, t, steps[j], fmi3True, &event, &terminate, &early, &last));
            t = last;
            CHECK(fmi3GetFloat64(fmu, vr, N_VR, values, N_VR));
        }
        CHECK(fmi3GetDirectionalDerivative(fmu, unknowns, N_UNKNOWNS, knowns, N_KNOWNS, seed,
                                           N_KNOWNS, sensitivity, N_UNKNOWNS));
        CHECK(fmi3GetAdjointDerivative(fmu, unknowns, N_UNKNOWNS, knowns, N_KNOWNS, seed,
                                       N_UNKNOWNS, sensitivity, N_KNOWNS));
        size_t size = 0;
        CHECK(fmi3SerializedFMUStateSize(fmu, state, &size));
        unsigned char buffer[4096];
        if (size > sizeof buffer) return 3;
        CHECK(fmi3SerializeFMUState(fmu, state, buffer, size));
        CHECK(fmi3DeserializeFMUState(fmu, buffer, size, &copy));
        CHECK(fmi3SetFMUState(fmu, round == 0 ? copy : state));
        t = 0.0;
    }
    CHECK(fmi3FreeFMUState(fmu, &copy));
    /* the state is left for fmi3FreeInstance to free */
    CHECK(fmi3Terminate(fmu));
    return 0;
}

int main(void)
{
    fmi3Instance cs = fmi3InstantiateCoSimulation("cs", TOKEN, NULL, fmi3False, fmi3True,
                                                  EVENT_MODE, fmi3False, NULL, 0, NULL, logger, NULL);
    if (!cs || exercise(cs, EVENT_MODE)) return 2;
    fmi3FreeInstance(cs);
#if HAS_ME
    fmi3Instance me = fmi3InstantiateModelExchange("me", TOKEN, NULL, fmi3False, fmi3True, NULL, logger);
    if (!me) return 4;
    fmi3Float64 x[N_STATES], dx[N_STATES], nominal[N_STATES];
    fmi3Boolean a, b, c, d, e;
    fmi3Float64 next;
    CHECK(fmi3EnterInitializationMode(me, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    CHECK(fmi3ExitInitializationMode(me));
    CHECK(fmi3UpdateDiscreteStates(me, &a, &b, &c, &d, &e, &next));
    CHECK(fmi3EnterContinuousTimeMode(me));
    fmi3FMUState state = NULL;
    CHECK(fmi3GetFMUState(me, &state));
    for (int i = 0; i < N_STATES; i++) x[i] = 0.5 * i;
    CHECK(fmi3SetContinuousStates(me, x, N_STATES));
    CHECK(fmi3GetContinuousStateDerivatives(me, dx, N_STATES));
    CHECK(fmi3GetNominalsOfContinuousStates(me, nominal, N_STATES));
    CHECK(fmi3SetFMUState(me, state));
    CHECK(fmi3FreeFMUState(me, &state));
    fmi3FreeInstance(me);
#endif
    printf(errors ? "errors\n" : "done\n");
    return 0;
}
"""

HARNESS2 = r"""
#include <stdio.h>
#include <stdlib.h>
#include "fmi2Functions.h"

static int errors = 0;
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                   fmi2String m, ...)
{
    (void)e; (void)n; (void)c;
    if (s >= fmi2Error) { errors++; printf("log: %s\n", m); }
}

#define CHECK(call) do { if ((call) > fmi2Discard) { printf("failed: %s\n", #call); return 1; } } while (0)

int main(void)
{
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component fmu = fmi2Instantiate("cs", fmi2CoSimulation, TOKEN, "", &callbacks,
                                        fmi2False, fmi2False);
    if (!fmu) return 2;
    fmi2ValueReference vr[N_VR], unknowns[N_UNKNOWNS], knowns[N_KNOWNS];
    fmi2Real values[N_VR], seed[N_VR], sensitivity[N_VR];
    for (int i = 0; i < N_VR; i++) { vr[i] = (fmi2ValueReference)i; seed[i] = 1.0 + i; }
    for (int i = 0; i < N_UNKNOWNS; i++) unknowns[i] = FIRST_UNKNOWN[i];
    for (int i = 0; i < N_KNOWNS; i++) knowns[i] = FIRST_KNOWN[i];
    CHECK(fmi2SetupExperiment(fmu, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(fmu));
    CHECK(fmi2ExitInitializationMode(fmu));
    fmi2FMUstate state = NULL, copy = NULL;
    CHECK(fmi2GetFMUstate(fmu, &state));
    const double steps[] = {STEP, 0.037, 2.5 * STEP, 1000.5 * STEP, 5.0, 1e-6};
    for (int round = 0; round < 2; round++) {
        double t = 0.0;
        for (size_t j = 0; j < sizeof steps / sizeof steps[0]; j++) {
            CHECK(fmi2DoStep(fmu, t, steps[j], fmi2True));
            t += steps[j];
            CHECK(fmi2GetReal(fmu, vr, N_VR, values));
        }
        CHECK(fmi2GetDirectionalDerivative(fmu, unknowns, N_UNKNOWNS, knowns, N_KNOWNS, seed,
                                           sensitivity));
        size_t size = 0;
        CHECK(fmi2SerializedFMUstateSize(fmu, state, &size));
        fmi2Byte buffer[4096];
        if (size > sizeof buffer) return 3;
        CHECK(fmi2SerializeFMUstate(fmu, state, buffer, size));
        CHECK(fmi2DeSerializeFMUstate(fmu, buffer, size, &copy));
        CHECK(fmi2SetFMUstate(fmu, round == 0 ? copy : state));
    }
    CHECK(fmi2FreeFMUstate(fmu, &copy));
    CHECK(fmi2Terminate(fmu));
    fmi2FreeInstance(fmu);
    printf(errors ? "errors\n" : "done\n");
    return 0;
}
"""


def layout(name: str, version: str) -> dict[str, str]:
    """Macros of the harness for one exported FMU, from its modelDescription.xml."""
    description = read_model_description(str(exported(name, version)))
    variables = description.modelVariables
    inputs = [v for v in variables if v.causality == "input" and v.type != "Clock"]
    outputs = [v for v in variables if v.causality == "output"]
    states = [v for v in variables if v.causality == "local" and not v.name.startswith("der(")]
    derivatives = [v for v in variables if v.name.startswith("der(")]
    sampled = any(v.variability == "discrete" for v in states)  # discrete-time states
    unknowns = [v.valueReference for v in outputs + derivatives]
    knowns = [v.valueReference for v in inputs + ([] if sampled else states)]
    clock = [v.valueReference for v in variables if v.type == "Clock"]

    def array(values):
        return "((const unsigned[]){" + ",".join(map(str, values)) + "})"

    return {"TOKEN": f'"{description.guid}"',
            "N_VR": str(len(inputs) + len(outputs) + len(states) + len(derivatives)),
            "N_INPUTS": str(len(inputs)), "N_STATES": str(len(states)),
            "N_UNKNOWNS": str(len(unknowns)), "N_KNOWNS": str(len(knowns)),
            "FIRST_UNKNOWN": array(unknowns), "FIRST_KNOWN": array(knowns),
            "STEP": repr(SAMPLE_TIME if name in ("lqr", "plant") else 0.01),
            "EVENT_MODE": "1" if clock else "0", "CLOCK_VR": str(clock[0] if clock else 0),
            "HAS_ME": "0" if sampled else "1"}


@pytest.mark.slow
@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["hub", "lqr"])
def test_sources_are_clean_under_address_and_undefined_behaviour_sanitizers(name, version, tmp_path):
    folder = tmp_path / "fmu"
    with zipfile.ZipFile(exported(name, version)) as archive:
        archive.extractall(folder)
    sources = folder / "sources"
    api = "fmi2Functions.c" if version == "2.0" else "fmi3Functions.c"
    files = [str(sources / f) for f in ("model.c", api, "lti_instance.c", "linear_model.c")]
    (tmp_path / "main.c").write_text(HARNESS2 if version == "2.0" else HARNESS3)
    defines = [f"-D{k}={v}" for k, v in layout(name, version).items()]
    headers = Path(fmpy.__file__).parent / "c-code" if version == "3.0" else sources
    subprocess.run(["gcc", *FLAGS, *defines, f"-I{sources}", f"-I{headers}",
                    str(tmp_path / "main.c"), *files, "-o", str(tmp_path / "harness"), "-lm",
                    "-pthread"], check=True, capture_output=True, text=True)
    result = subprocess.run([str(tmp_path / "harness")], capture_output=True, text=True, timeout=120)
    assert "Sanitizer" not in result.stderr and "runtime error" not in result.stderr, result.stderr[:3000]
    assert result.returncode == 0 and result.stdout.endswith("done\n"), result.stdout + result.stderr


HARNESS_THREADS = r"""
#include <pthread.h>
#include <stdio.h>
#include "fmi3Functions.h"

/* Threads create, step, save and restore and free instances of one FMU at the same time:
 * they share only the list of live instances. */
static void *work(void *arg)
{
    (void)arg;
    for (int round = 0; round < 50; round++) {
        fmi3Instance fmu = fmi3InstantiateCoSimulation("t", TOKEN, NULL, fmi3False, fmi3False,
                                                       fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
        if (!fmu) return (void *)1;
        fmi3FMUState state = NULL;
        fmi3Boolean a, b, c;
        fmi3Float64 last;
        if (fmi3EnterInitializationMode(fmu, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK
            || fmi3ExitInitializationMode(fmu) != fmi3OK
            || fmi3GetFMUState(fmu, &state) != fmi3OK
            || fmi3DoStep(fmu, 0.0, 0.037, fmi3True, &a, &b, &c, &last) != fmi3OK
            || fmi3SetFMUState(fmu, state) != fmi3OK) return (void *)2;
        fmi3FreeInstance(fmu);
    }
    return NULL;
}

int main(void)
{
    pthread_t threads[4];
    for (int i = 0; i < 4; i++) pthread_create(&threads[i], NULL, work, NULL);
    int bad = 0;
    for (int i = 0; i < 4; i++) {
        void *result;
        pthread_join(threads[i], &result);
        bad |= result != NULL;
    }
    printf(bad ? "failed\n" : "done\n");
    return bad;
}
"""


@pytest.mark.slow
def test_instances_in_threads_under_thread_sanitizer(tmp_path):
    """Four threads, 50 instances each, under ThreadSanitizer: no data race."""
    folder = tmp_path / "fmu"
    with zipfile.ZipFile(exported("hub", "3.0")) as archive:
        archive.extractall(folder)
    sources = folder / "sources"
    token = read_model_description(str(exported("hub", "3.0"))).guid
    headers = Path(fmpy.__file__).parent / "c-code"
    files = [str(sources / f) for f in ("model.c", "fmi3Functions.c", "lti_instance.c", "linear_model.c")]
    (tmp_path / "main.c").write_text(HARNESS_THREADS)
    subprocess.run(["gcc", "-std=c99", "-g", "-O1", "-fsanitize=thread", f'-DTOKEN="{token}"',
                    f"-I{sources}", f"-I{headers}", str(tmp_path / "main.c"), *files,
                    "-o", str(tmp_path / "threads"), "-lm", "-pthread"], check=True,
                   capture_output=True, text=True)
    result = subprocess.run([str(tmp_path / "threads")], capture_output=True, text=True, timeout=300)
    assert "ThreadSanitizer" not in result.stderr, result.stderr[:3000]
    assert result.returncode == 0 and result.stdout == "done\n", result.stdout + result.stderr
