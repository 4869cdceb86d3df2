/* flexsat FMU template: the FMI 2.0 API layer (Model Exchange and Co-Simulation).
 *
 * One binary serves both interfaces.  This file checks every call (instance pointer, state
 * machine, value references, null arrays, non-finite numbers), logs what went wrong through
 * the environment's logger and returns fmi2Error or fmi2Discard instead of crashing.  The
 * values, stepping, FMU states and partial derivatives are in lti_instance.c (shared with
 * the FMI 3.0 layer), the arithmetic in linear_model.c, the system's matrices in the
 * generated model.c.
 *
 * Which interfaces the library provides is set by the generated flexsat_interfaces.h
 * (FLEXSAT_MODEL_EXCHANGE, FLEXSAT_CO_SIMULATION, as declared in modelDescription.xml): the
 * library exports exactly the fmi2 functions of those interfaces.
 *
 * Instances: every live instance is on a list guarded by a mutex (lti_instance.c), and each
 * call first looks its fmi2Component up there by address, without dereferencing it.  A stale handle -
 * e.g. a second fmi2FreeInstance, which the standard leaves undefined - is therefore
 * refused without reading freed memory, unless the allocator has since handed the same
 * address to a new instance of this FMU (then the handle is that instance: no handle
 * scheme that returns plain pointers can tell the two apart).  Freed instances are
 * cleared before their memory is released.
 *
 * Value references: see lti_instance.h (inputs, outputs, states, derivatives).
 *
 * FMU states (canGetAndSetFMUstate, canSerializeFMUstate) hold the time, the states, the
 * inputs and, for a sampled model, the sample index and the held outputs: restoring one
 * and stepping again repeats the same computation, bit for bit.  Directional derivatives
 * (providesDirectionalDerivative) are the entries of A, B, C, D.  A discrete-time model
 * (Co-Simulation only) samples every T whatever the communication step, holding its
 * outputs between samples (lti_instance.h).
 *
 * Reference: FMI 2.0.1 standard (Modelica Association, 2019), section 2.1 (common API and
 * state machine), 3.2 (Model Exchange), 4.2 (Co-Simulation).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "flexsat_interfaces.h"
#include "linear_model.h"
#include "lti_instance.h"

#if !FLEXSAT_MODEL_EXCHANGE && !FLEXSAT_CO_SIMULATION
#error "flexsat_interfaces.h must enable FLEXSAT_MODEL_EXCHANGE or FLEXSAT_CO_SIMULATION"
#endif

#define INSTANCE_MAGIC 0x464c5853u /* "FLXS": detects stale or foreign handles */

typedef enum {
    STATE_INSTANTIATED = 1 << 0,
    STATE_INITIALIZATION = 1 << 1,
    STATE_EVENT = 1 << 2,
    STATE_CONTINUOUS = 1 << 3,
    STATE_STEP_COMPLETE = 1 << 4,
    STATE_STEP_FAILED = 1 << 5,
    STATE_TERMINATED = 1 << 6,
    STATE_ERROR = 1 << 7
} ModelState;

#define ANY_STATE 0xFFFF
#define AFTER_INIT (STATE_EVENT | STATE_CONTINUOUS | STATE_STEP_COMPLETE)
#define READABLE (STATE_INITIALIZATION | STATE_EVENT | STATE_CONTINUOUS | STATE_STEP_COMPLETE \
                  | STATE_STEP_FAILED | STATE_TERMINATED | STATE_ERROR)

typedef struct Instance {
    LiNode node; /* first member: the list of live instances */
    unsigned magic;
    fmi2Type type;
    char *instance_name;
    fmi2CallbackLogger logger;
    fmi2CallbackFreeMemory free_memory;
    fmi2ComponentEnvironment environment;
    int logging_on;
    ModelState state;
    LiValues values;
} Instance;

static const LinearModel *const model = &linear_model;

static size_t n_st(void) { return model->n_states; }

/* ---------------------------------------------------------------- logging */

static void log_message(Instance *inst, fmi2Status status, const char *category,
                        const char *format, ...)
{
    char text[512], escaped[1024];
    va_list args;
    if (inst == NULL || inst->logger == NULL) return;
    /* errors are always reported; other messages only with debug logging on */
    if (status < fmi2Error && !inst->logging_on) return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    /* the logger treats the message as a printf format: escape '%' */
    size_t j = 0;
    for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    inst->logger(inst->environment, inst->instance_name, status, category, escaped);
}

#define LOG_ERROR(inst, ...) log_message((inst), fmi2Error, "logStatusError", __VA_ARGS__)
#define LOG_WARNING(inst, ...) log_message((inst), fmi2Warning, "logStatusWarning", __VA_ARGS__)

/* ---------------------------------------------------------------- checks */

static Instance *as_instance(fmi2Component c)
{
    /* node is the first member: the node's address is the instance's */
    Instance *inst = (Instance *)li_find(c, 0);
    if (inst == NULL || inst->magic != INSTANCE_MAGIC) return NULL;
    return inst;
}

static const char *state_name(ModelState state)
{
    switch (state) {
    case STATE_INSTANTIATED: return "Instantiated";
    case STATE_INITIALIZATION: return "InitializationMode";
    case STATE_EVENT: return "EventMode";
    case STATE_CONTINUOUS: return "ContinuousTimeMode";
    case STATE_STEP_COMPLETE: return "StepComplete";
    case STATE_STEP_FAILED: return "StepFailed";
    case STATE_TERMINATED: return "Terminated";
    case STATE_ERROR: return "Error";
    }
    return "unknown";
}

/* Returns the instance if the call is allowed in its current state, else NULL (logged). */
static Instance *checked(fmi2Component c, const char *function, int allowed_states)
{
    Instance *inst = as_instance(c);
    if (inst == NULL) return NULL;
    if (!(inst->state & allowed_states)) {
        LOG_ERROR(inst, "%s must not be called in state %s.", function, state_name(inst->state));
        return NULL;
    }
    return inst;
}

static int null_array(Instance *inst, const char *function, const char *argument,
                      const void *pointer, size_t count)
{
    if (count > 0 && pointer == NULL) {
        LOG_ERROR(inst, "%s: argument %s is NULL although %lu values were requested.",
                  function, argument, (unsigned long)count);
        return 1;
    }
    return 0;
}

/* ---------------------------------------------------------------- common functions */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn,
                                           size_t nCategories, const fmi2String categories[])
{
    Instance *inst = checked(c, "fmi2SetDebugLogging", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    if (null_array(inst, "fmi2SetDebugLogging", "categories", categories, nCategories))
        return fmi2Error;
    for (size_t i = 0; i < nCategories; i++) {
        if (categories[i] == NULL || (strcmp(categories[i], "logStatusError") != 0
                                      && strcmp(categories[i], "logStatusWarning") != 0)) {
            LOG_ERROR(inst, "fmi2SetDebugLogging: unknown log category \"%s\"; expected "
                      "logStatusError or logStatusWarning.",
                      categories[i] == NULL ? "(null)" : categories[i]);
            return fmi2Error;
        }
    }
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

/* Release an instance that is not (or no longer) on the live list. */
static void free_instance(Instance *inst)
{
    fmi2CallbackFreeMemory release = inst->free_memory;
    char *name = inst->instance_name;
    li_free(&inst->values);
    memset(inst, 0, sizeof *inst); /* no magic, no pointers left behind */
    if (name != NULL) release(name);
    release(inst);
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                          fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                          const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL) return NULL;

    /* a temporary instance lets the error messages below go through the logger */
    Instance report = {0};
    report.magic = INSTANCE_MAGIC;
    report.logger = functions->logger;
    report.environment = functions->componentEnvironment;
    report.instance_name = (char *)(instanceName != NULL ? instanceName : "(null)");

    if (instanceName == NULL || instanceName[0] == '\0') {
        LOG_ERROR(&report, "fmi2Instantiate: instanceName must be a non-empty string.");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, model->guid) != 0) {
        LOG_ERROR(&report, "fmi2Instantiate: wrong GUID %s; this binary is %s with GUID %s.",
                  fmuGUID == NULL ? "(null)" : fmuGUID, model->model_name, model->guid);
        return NULL;
    }
    if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation) {
        LOG_ERROR(&report, "fmi2Instantiate: unknown fmuType %d.", (int)fmuType);
        return NULL;
    }
    if ((fmuType == fmi2ModelExchange && (!FLEXSAT_MODEL_EXCHANGE || li_discrete()))
        || (fmuType == fmi2CoSimulation && !FLEXSAT_CO_SIMULATION)) {
        LOG_ERROR(&report, "fmi2Instantiate: this FMU does not provide %s (see "
                  "modelDescription.xml).",
                  fmuType == fmi2ModelExchange ? "Model Exchange" : "Co-Simulation");
        return NULL;
    }
    if ((functions->allocateMemory == NULL) != (functions->freeMemory == NULL)) {
        LOG_ERROR(&report, "fmi2Instantiate: allocateMemory and freeMemory must both be given "
                  "or both be NULL.");
        return NULL;
    }

    fmi2CallbackAllocateMemory allocate =
        functions->allocateMemory != NULL ? functions->allocateMemory : calloc;
    fmi2CallbackFreeMemory release = functions->freeMemory != NULL ? functions->freeMemory : free;

    Instance *inst = (Instance *)allocate(1, sizeof(Instance));
    if (inst == NULL) {
        LOG_ERROR(&report, "fmi2Instantiate: out of memory.");
        return NULL;
    }
    memset(inst, 0, sizeof *inst);
    inst->free_memory = release;
    inst->magic = INSTANCE_MAGIC;
    inst->type = fmuType;
    inst->logger = functions->logger;
    inst->environment = functions->componentEnvironment;
    inst->logging_on = loggingOn ? 1 : 0;
    inst->state = STATE_INSTANTIATED;

    inst->instance_name = (char *)allocate(strlen(instanceName) + 1, 1);
    if (inst->instance_name == NULL
        || li_allocate(&inst->values, allocate, release, fmuType == fmi2CoSimulation) != 0) {
        LOG_ERROR(&report, "fmi2Instantiate: out of memory.");
        free_instance(inst);
        return NULL;
    }
    strcpy(inst->instance_name, instanceName);
    li_register(&inst->node);
    return inst;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    /* taken off the live list first: a second call with the same handle finds nothing */
    Instance *inst = (Instance *)li_find(c, 1);
    if (inst != NULL) free_instance(inst);
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                                           fmi2Real tolerance, fmi2Real startTime,
                                           fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    Instance *inst = checked(c, "fmi2SetupExperiment", STATE_INSTANTIATED);
    if (inst == NULL) return fmi2Error;
    if (!isfinite(startTime)) {
        LOG_ERROR(inst, "fmi2SetupExperiment: startTime must be finite [s]; got %g.", startTime);
        return fmi2Error;
    }
    if (stopTimeDefined && !(stopTime >= startTime)) {
        LOG_ERROR(inst, "fmi2SetupExperiment: stopTime must be >= startTime [s]; got %g < %g.",
                  stopTime, startTime);
        return fmi2Error;
    }
    li_start(&inst->values, startTime);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *inst = checked(c, "fmi2EnterInitializationMode", STATE_INSTANTIATED);
    if (inst == NULL) return fmi2Error;
    inst->state = STATE_INITIALIZATION;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *inst = checked(c, "fmi2ExitInitializationMode", STATE_INITIALIZATION);
    if (inst == NULL) return fmi2Error;
    inst->state = inst->type == fmi2ModelExchange ? STATE_EVENT : STATE_STEP_COMPLETE;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance *inst = checked(c, "fmi2Terminate",
                             STATE_EVENT | STATE_CONTINUOUS | STATE_STEP_COMPLETE
                             | STATE_STEP_FAILED);
    if (inst == NULL) return fmi2Error;
    inst->state = STATE_TERMINATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *inst = checked(c, "fmi2Reset", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    li_reset(&inst->values);
    inst->state = STATE_INSTANTIATED;
    return fmi2OK;
}

/* An output or derivative that is not finite (C x + D u or A x + B u overflowed for finite
 * x and u): fmi2Discard in Model Exchange, where the integrator can retry with a smaller
 * step (FMI 2.0.1, section 2.1.3), fmi2Error in Co-Simulation, where fmi2DoStep already
 * refused to reach such a state and only the inputs set since can have caused it. */
static fmi2Status overflowed(Instance *inst, const char *function, const char *what,
                             const char *name)
{
    LOG_ERROR(inst, "%s: %s %s is not finite at t = %g s (the linear model overflows for "
              "these states and inputs).", function, what, name, inst->values.time);
    return inst->type == fmi2ModelExchange ? fmi2Discard : fmi2Error;
}

/* ---------------------------------------------------------------- variable access */

/* The variables of FMI 2.0: inputs, outputs, states, derivatives (the time is not one). */
static LiKind kind_of(fmi2ValueReference vr, size_t *index)
{
    const LiKind kind = li_kind((unsigned long)vr, index);
    return kind == LI_TIME || kind == LI_CLOCK ? LI_INVALID : kind;
}

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   fmi2Real value[])
{
    Instance *inst = checked(c, "fmi2GetReal", READABLE);
    if (inst == NULL) return fmi2Error;
    if (null_array(inst, "fmi2GetReal", "vr", vr, nvr)
        || null_array(inst, "fmi2GetReal", "value", value, nvr))
        return fmi2Error;
    /* outputs and derivatives from the current inputs: direct feedthrough is never stale */
    LiValues *v = &inst->values;
    li_update_outputs(v);
    if (!li_discrete()) li_update_derivatives(v);
    for (size_t i = 0; i < nvr; i++) {
        size_t k;
        switch (kind_of(vr[i], &k)) {
        case LI_INPUT: value[i] = v->u[k]; break;
        case LI_OUTPUT: value[i] = v->y[k]; break;
        case LI_STATE: value[i] = v->x[k]; break;
        case LI_DERIVATIVE: value[i] = v->dx[k]; break;
        default:
            LOG_ERROR(inst, "fmi2GetReal: unknown value reference %u.", (unsigned)vr[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        size_t k;
        const LiKind kind = kind_of(vr[i], &k);
        if ((kind == LI_OUTPUT || kind == LI_DERIVATIVE) && !isfinite(value[i]))
            return overflowed(inst, "fmi2GetReal",
                              kind == LI_OUTPUT ? "output" : "derivative of state",
                              kind == LI_OUTPUT ? model->output_names[k]
                                                : model->state_names[k]);
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Real value[])
{
    Instance *inst = checked(c, "fmi2SetReal", STATE_INSTANTIATED | STATE_INITIALIZATION
                                                   | AFTER_INIT);
    if (inst == NULL) return fmi2Error;
    if (null_array(inst, "fmi2SetReal", "vr", vr, nvr)
        || null_array(inst, "fmi2SetReal", "value", value, nvr))
        return fmi2Error;
    const int before_init = inst->state & (STATE_INSTANTIATED | STATE_INITIALIZATION);
    /* check everything first so that a rejected call changes nothing */
    for (size_t i = 0; i < nvr; i++) {
        size_t k;
        const LiKind kind = kind_of(vr[i], &k);
        if (kind == LI_INVALID) {
            LOG_ERROR(inst, "fmi2SetReal: unknown value reference %u.", (unsigned)vr[i]);
            return fmi2Error;
        }
        if (kind == LI_OUTPUT || kind == LI_DERIVATIVE) {
            LOG_ERROR(inst, "fmi2SetReal: %s is calculated and cannot be set.",
                      kind == LI_OUTPUT ? model->output_names[k] : "a state derivative");
            return fmi2Error;
        }
        if (kind == LI_STATE && !before_init) {
            LOG_ERROR(inst, "fmi2SetReal: state %s can only be set before initialisation "
                      "is finished (use fmi2SetContinuousStates in Model Exchange).",
                      model->state_names[k]);
            return fmi2Error;
        }
        if (!isfinite(value[i])) {
            LOG_ERROR(inst, "fmi2SetReal: %s %s must be finite; got %g. The value was not set.",
                      kind == LI_INPUT ? "input" : "state",
                      kind == LI_INPUT ? model->input_names[k] : model->state_names[k],
                      value[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        size_t k = 0;
        if (kind_of(vr[i], &k) == LI_INPUT) inst->values.u[k] = value[i];
        else inst->values.x[k] = value[i];
    }
    return fmi2OK;
}

/* This model has no Integer, Boolean or String variables. */
static fmi2Status no_such_variables(fmi2Component c, const char *function, int allowed,
                                    const fmi2ValueReference vr[], size_t nvr)
{
    Instance *inst = checked(c, function, allowed);
    if (inst == NULL) return fmi2Error;
    if (nvr > 0) {
        LOG_ERROR(inst, "%s: unknown value reference %u (this model has only Real variables).",
                  function, vr == NULL ? 0u : (unsigned)vr[0]);
        return fmi2Error;
    }
    return fmi2OK;
}

#define SETTABLE (STATE_INSTANTIATED | STATE_INITIALIZATION | AFTER_INIT)

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, fmi2Integer value[])
{
    (void)value;
    return no_such_variables(c, "fmi2GetInteger", READABLE, vr, nvr);
}

FMI2_Export fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, fmi2Boolean value[])
{
    (void)value;
    return no_such_variables(c, "fmi2GetBoolean", READABLE, vr, nvr);
}

FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[],
                                     size_t nvr, fmi2String value[])
{
    (void)value;
    return no_such_variables(c, "fmi2GetString", READABLE, vr, nvr);
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, const fmi2Integer value[])
{
    (void)value;
    return no_such_variables(c, "fmi2SetInteger", SETTABLE, vr, nvr);
}

FMI2_Export fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, const fmi2Boolean value[])
{
    (void)value;
    return no_such_variables(c, "fmi2SetBoolean", SETTABLE, vr, nvr);
}

FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[],
                                     size_t nvr, const fmi2String value[])
{
    (void)value;
    return no_such_variables(c, "fmi2SetString", SETTABLE, vr, nvr);
}

/* ---------------------------------------------------------------- unsupported capabilities */

static fmi2Status unsupported(fmi2Component c, const char *function, const char *capability)
{
    Instance *inst = as_instance(c);
    LOG_ERROR(inst, "%s is not supported (%s=\"false\" in modelDescription.xml).", function,
              capability);
    return fmi2Error;
}

/* ---------------------------------------------------------------- FMU states */

/* The FMU state functions are allowed in every state of the instance.  An FMU state holds
 * the mode too (lti_instance.c), for the kind of instance it was saved by. */
static unsigned kind_code(const Instance *inst) { return inst->type == fmi2CoSimulation ? 1u : 0u; }

static unsigned valid_modes(const Instance *inst)
{
    const unsigned common = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_TERMINATED
                            | STATE_ERROR;
    return inst->type == fmi2CoSimulation ? common | STATE_STEP_COMPLETE | STATE_STEP_FAILED
                                          : common | STATE_EVENT | STATE_CONTINUOUS;
}

static LiSnapshot *our_state(Instance *inst, const char *function, fmi2FMUstate FMUstate)
{
    LiSnapshot *state = li_find_snapshot(&inst->values, FMUstate);
    if (state == NULL)
        LOG_ERROR(inst, "%s: FMUstate is not a state of this instance (NULL, freed, or "
                  "another instance's).", function);
    return state;
}

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *inst = checked(c, "fmi2GetFMUstate", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    if (FMUstate == NULL) {
        LOG_ERROR(inst, "fmi2GetFMUstate: argument FMUstate is NULL.");
        return fmi2Error;
    }
    LiSnapshot *state = (LiSnapshot *)*FMUstate;
    const int status = li_save(&inst->values, &state, (unsigned)inst->state, kind_code(inst));
    if (status == -2) {
        LOG_ERROR(inst, "fmi2GetFMUstate: *FMUstate must be NULL (a new state) or a state of "
                  "this instance to overwrite; got another pointer.");
        return fmi2Error;
    }
    if (status != 0) {
        LOG_ERROR(inst, "fmi2GetFMUstate: out of memory.");
        return fmi2Error;
    }
    *FMUstate = state;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance *inst = checked(c, "fmi2SetFMUstate", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    LiSnapshot *state = our_state(inst, "fmi2SetFMUstate", FMUstate);
    if (state == NULL) return fmi2Error;
    li_restore(&inst->values, state);
    /* the mode is part of the state (a rollback after a discarded step may step on) */
    inst->state = (ModelState)li_snapshot_mode(state);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *inst = checked(c, "fmi2FreeFMUstate", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    if (FMUstate == NULL) {
        LOG_ERROR(inst, "fmi2FreeFMUstate: argument FMUstate is NULL.");
        return fmi2Error;
    }
    if (*FMUstate == NULL) return fmi2OK; /* nothing to free */
    if (li_discard(&inst->values, (LiSnapshot *)*FMUstate) != 0) {
        LOG_ERROR(inst, "fmi2FreeFMUstate: *FMUstate is not a state of this instance (freed "
                  "already, or another instance's).");
        return fmi2Error;
    }
    *FMUstate = NULL;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate,
                                                  size_t *size)
{
    Instance *inst = checked(c, "fmi2SerializedFMUstateSize", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    if (our_state(inst, "fmi2SerializedFMUstateSize", FMUstate) == NULL) return fmi2Error;
    if (size == NULL) {
        LOG_ERROR(inst, "fmi2SerializedFMUstateSize: argument size is NULL.");
        return fmi2Error;
    }
    *size = li_serialized_size();
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                             fmi2Byte serializedState[], size_t size)
{
    Instance *inst = checked(c, "fmi2SerializeFMUstate", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    LiSnapshot *state = our_state(inst, "fmi2SerializeFMUstate", FMUstate);
    if (state == NULL) return fmi2Error;
    if (null_array(inst, "fmi2SerializeFMUstate", "serializedState", serializedState, size))
        return fmi2Error;
    if (size < li_serialized_size()) {
        LOG_ERROR(inst, "fmi2SerializeFMUstate: size must be at least %lu bytes (see "
                  "fmi2SerializedFMUstateSize); got %lu.", (unsigned long)li_serialized_size(),
                  (unsigned long)size);
        return fmi2Error;
    }
    li_serialize(state, (unsigned char *)serializedState);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c,
                                               const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate *FMUstate)
{
    Instance *inst = checked(c, "fmi2DeSerializeFMUstate", ANY_STATE);
    if (inst == NULL) return fmi2Error;
    if (FMUstate == NULL || null_array(inst, "fmi2DeSerializeFMUstate", "serializedState",
                                       serializedState, size)) {
        if (FMUstate == NULL) LOG_ERROR(inst, "fmi2DeSerializeFMUstate: argument FMUstate is NULL.");
        return fmi2Error;
    }
    LiSnapshot *state = (LiSnapshot *)*FMUstate;
    const char *why = NULL;
    const int status = li_deserialize(&inst->values, (const unsigned char *)serializedState,
                                      size, kind_code(inst), valid_modes(inst), &state, &why);
    if (status != 0) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: the %lu bytes are not a serialized state of "
                  "this model: %s.", (unsigned long)size, why != NULL ? why : "out of memory");
        return fmi2Error;
    }
    *FMUstate = state;
    return fmi2OK;
}

/* ---------------------------------------------------------------- partial derivatives */

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
                                                    const fmi2ValueReference vUnknown_ref[],
                                                    size_t nUnknown,
                                                    const fmi2ValueReference vKnown_ref[],
                                                    size_t nKnown, const fmi2Real dvKnown[],
                                                    fmi2Real dvUnknown[])
{
    static const char *const function = "fmi2GetDirectionalDerivative";
    Instance *inst = checked(c, function, READABLE);
    if (inst == NULL) return fmi2Error;
    if (null_array(inst, function, "vUnknown_ref", vUnknown_ref, nUnknown)
        || null_array(inst, function, "vKnown_ref", vKnown_ref, nKnown)
        || null_array(inst, function, "dvKnown", dvKnown, nKnown)
        || null_array(inst, function, "dvUnknown", dvUnknown, nUnknown))
        return fmi2Error;
    for (size_t k = 0; k < nKnown; k++) {
        if (!isfinite(dvKnown[k])) {
            LOG_ERROR(inst, "%s: dvKnown[%lu] must be finite; got %g.", function,
                      (unsigned long)k, dvKnown[k]);
            return fmi2Error;
        }
    }
    /* check every reference first: a refused call writes nothing */
    for (size_t i = 0; i < nUnknown; i++) {
        size_t row;
        if (!li_is_unknown(kind_of(vUnknown_ref[i], &row))) {
            LOG_ERROR(inst, "%s: value reference %u is not an unknown of this model (%s).",
                      function, (unsigned)vUnknown_ref[i],
                      li_discrete() ? "an output" : "an output or a state derivative");
            return fmi2Error;
        }
    }
    for (size_t k = 0; k < nKnown; k++) {
        size_t column;
        if (!li_is_known(kind_of(vKnown_ref[k], &column))) {
            LOG_ERROR(inst, "%s: value reference %u is not a known of this model (%s).",
                      function, (unsigned)vKnown_ref[k],
                      li_discrete() ? "an input" : "an input or a state");
            return fmi2Error;
        }
    }
    /* dvUnknown = J dvKnown, J the block of [[A, B], [C, D]] (lti_instance.h) */
    for (size_t i = 0; i < nUnknown; i++) {
        size_t row, column;
        const LiKind unknown = kind_of(vUnknown_ref[i], &row);
        double sum = 0.0;
        for (size_t k = 0; k < nKnown; k++) {
            const LiKind known = kind_of(vKnown_ref[k], &column);
            sum += li_partial(&inst->values, unknown, row, known, column) * dvKnown[k];
        }
        dvUnknown[i] = sum;
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- Model Exchange */
#if FLEXSAT_MODEL_EXCHANGE

static Instance *checked_me(fmi2Component c, const char *function, int allowed)
{
    Instance *inst = as_instance(c);
    if (inst != NULL && inst->type != fmi2ModelExchange) {
        LOG_ERROR(inst, "%s is a Model Exchange function; this instance is Co-Simulation.",
                  function);
        return NULL;
    }
    return checked(c, function, allowed);
}

FMI2_Export fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    Instance *inst = checked_me(c, "fmi2EnterEventMode", STATE_EVENT | STATE_CONTINUOUS);
    if (inst == NULL) return fmi2Error;
    inst->state = STATE_EVENT;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    Instance *inst = checked_me(c, "fmi2NewDiscreteStates", STATE_EVENT);
    if (inst == NULL) return fmi2Error;
    if (eventInfo == NULL) {
        LOG_ERROR(inst, "fmi2NewDiscreteStates: argument eventInfo is NULL.");
        return fmi2Error;
    }
    /* a linear time-invariant system has no discrete states and no events */
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    Instance *inst = checked_me(c, "fmi2EnterContinuousTimeMode", STATE_EVENT);
    if (inst == NULL) return fmi2Error;
    inst->state = STATE_CONTINUOUS;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2CompletedIntegratorStep(fmi2Component c,
                                                   fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean *enterEventMode,
                                                   fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = checked_me(c, "fmi2CompletedIntegratorStep", STATE_CONTINUOUS);
    if (inst == NULL) return fmi2Error;
    if (enterEventMode == NULL || terminateSimulation == NULL) {
        LOG_ERROR(inst, "fmi2CompletedIntegratorStep: enterEventMode and terminateSimulation "
                  "must not be NULL.");
        return fmi2Error;
    }
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    Instance *inst = checked_me(c, "fmi2SetTime", STATE_EVENT | STATE_CONTINUOUS);
    if (inst == NULL) return fmi2Error;
    if (!isfinite(time)) {
        LOG_ERROR(inst, "fmi2SetTime: time must be finite [s]; got %g.", time);
        return fmi2Error;
    }
    inst->values.time = time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    Instance *inst = checked_me(c, "fmi2SetContinuousStates", STATE_CONTINUOUS);
    if (inst == NULL) return fmi2Error;
    if (nx != n_st()) {
        LOG_ERROR(inst, "fmi2SetContinuousStates: nx must be %lu; got %lu.",
                  (unsigned long)n_st(), (unsigned long)nx);
        return fmi2Error;
    }
    if (null_array(inst, "fmi2SetContinuousStates", "x", x, nx)) return fmi2Error;
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(x[i])) {
            LOG_ERROR(inst, "fmi2SetContinuousStates: state %s must be finite; got %g. "
                      "No state was set.", model->state_names[i], x[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nx; i++) inst->values.x[i] = x[i];
    return fmi2OK;
}

#define ME_READABLE (STATE_INITIALIZATION | STATE_EVENT | STATE_CONTINUOUS | STATE_TERMINATED \
                     | STATE_ERROR)

FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    Instance *inst = checked_me(c, "fmi2GetDerivatives", ME_READABLE);
    if (inst == NULL) return fmi2Error;
    if (nx != n_st()) {
        LOG_ERROR(inst, "fmi2GetDerivatives: nx must be %lu; got %lu.", (unsigned long)n_st(),
                  (unsigned long)nx);
        return fmi2Error;
    }
    if (null_array(inst, "fmi2GetDerivatives", "derivatives", derivatives, nx)) return fmi2Error;
    li_update_derivatives(&inst->values);
    for (size_t i = 0; i < nx; i++) derivatives[i] = inst->values.dx[i];
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(derivatives[i]))
            return overflowed(inst, "fmi2GetDerivatives", "derivative of state",
                              model->state_names[i]);
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[],
                                              size_t ni)
{
    (void)eventIndicators;
    Instance *inst = checked_me(c, "fmi2GetEventIndicators", ME_READABLE);
    if (inst == NULL) return fmi2Error;
    if (ni != 0) {
        LOG_ERROR(inst, "fmi2GetEventIndicators: this model has no event indicators; got "
                  "ni = %lu.", (unsigned long)ni);
        return fmi2Error;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    Instance *inst = checked_me(c, "fmi2GetContinuousStates", ME_READABLE);
    if (inst == NULL) return fmi2Error;
    if (nx != n_st()) {
        LOG_ERROR(inst, "fmi2GetContinuousStates: nx must be %lu; got %lu.",
                  (unsigned long)n_st(), (unsigned long)nx);
        return fmi2Error;
    }
    if (null_array(inst, "fmi2GetContinuousStates", "x", x, nx)) return fmi2Error;
    for (size_t i = 0; i < nx; i++) x[i] = inst->values.x[i];
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[],
                                                         size_t nx)
{
    Instance *inst = checked_me(c, "fmi2GetNominalsOfContinuousStates",
                                STATE_INSTANTIATED | ME_READABLE);
    if (inst == NULL) return fmi2Error;
    if (nx != n_st()) {
        LOG_ERROR(inst, "fmi2GetNominalsOfContinuousStates: nx must be %lu; got %lu.",
                  (unsigned long)n_st(), (unsigned long)nx);
        return fmi2Error;
    }
    if (null_array(inst, "fmi2GetNominalsOfContinuousStates", "x_nominal", x_nominal, nx))
        return fmi2Error;
    for (size_t i = 0; i < nx; i++) x_nominal[i] = model->nominals[i];
    return fmi2OK;
}

#endif /* FLEXSAT_MODEL_EXCHANGE */

/* ---------------------------------------------------------------- Co-Simulation */
#if FLEXSAT_CO_SIMULATION

static Instance *checked_cs(fmi2Component c, const char *function, int allowed)
{
    Instance *inst = as_instance(c);
    if (inst != NULL && inst->type != fmi2CoSimulation) {
        LOG_ERROR(inst, "%s is a Co-Simulation function; this instance is Model Exchange.",
                  function);
        return NULL;
    }
    return checked(c, function, allowed);
}

FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c,
                                                   const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[],
                                                   const fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs");
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c,
                                                    const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[],
                                                    fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder > 0");
}

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = checked_cs(c, "fmi2DoStep", STATE_STEP_COMPLETE);
    if (inst == NULL) return fmi2Error;
    const double t = currentCommunicationPoint, h = communicationStepSize;
    const double reached = inst->values.time;
    if (!(h > 0.0) || !isfinite(h)) {
        LOG_ERROR(inst, "fmi2DoStep: communicationStepSize must be positive and finite [s]; "
                  "got %g.", h);
        return fmi2Error;
    }
    if (!isfinite(t) || fabs(t - reached) > 1e-9 * (1.0 + fabs(reached))) {
        LOG_ERROR(inst, "fmi2DoStep: currentCommunicationPoint must equal the time reached "
                  "so far, %.17g s; got %.17g s.", reached, t);
        return fmi2Error;
    }
    size_t index;
    int detail;
    switch (li_do_step(&inst->values, t, h, &index, &detail)) {
    case LI_OK:
        return fmi2OK;
    case LI_NO_TRANSITION:
        LOG_ERROR(inst, "fmi2DoStep: the transition matrix for the step %g s is not "
                  "finite (code %d); the state was not changed.", h, detail);
        break;
    case LI_STATE_OVERFLOW:
        LOG_ERROR(inst, "fmi2DoStep: state %s overflowed at t = %g s; the state was "
                  "not changed.", model->state_names[index], t + h);
        break;
    case LI_OUTPUT_OVERFLOW:
        LOG_ERROR(inst, "fmi2DoStep: output %s overflowed at t = %g s; the state was "
                  "not changed.", model->output_names[index], t + h);
        break;
    default:
        LOG_ERROR(inst, "fmi2DoStep: the step of %g s spans 2^53 or more samples of the "
                  "sample period %g s; the state was not changed.", h, model->sample_period);
        break;
    }
    inst->state = STATE_STEP_FAILED;
    return fmi2Discard;
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c)
{
    Instance *inst = checked_cs(c, "fmi2CancelStep", STATE_STEP_COMPLETE);
    if (inst == NULL) return fmi2Error;
    LOG_ERROR(inst, "fmi2CancelStep: fmi2DoStep always completes synchronously; nothing to "
              "cancel.");
    return fmi2Error;
}

#define CS_STATUS_STATES (STATE_STEP_COMPLETE | STATE_STEP_FAILED | STATE_TERMINATED)

FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    Instance *inst = checked_cs(c, "fmi2GetStatus", CS_STATUS_STATES);
    if (inst == NULL) return fmi2Error;
    if (value == NULL) {
        LOG_ERROR(inst, "fmi2GetStatus: argument value is NULL.");
        return fmi2Error;
    }
    if (s != fmi2DoStepStatus) {
        LOG_ERROR(inst, "fmi2GetStatus: status kind %d is not available.", (int)s);
        return fmi2Discard;
    }
    *value = inst->state == STATE_STEP_FAILED ? fmi2Discard : fmi2OK;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s,
                                         fmi2Real *value)
{
    Instance *inst = checked_cs(c, "fmi2GetRealStatus", CS_STATUS_STATES);
    if (inst == NULL) return fmi2Error;
    if (value == NULL) {
        LOG_ERROR(inst, "fmi2GetRealStatus: argument value is NULL.");
        return fmi2Error;
    }
    if (s != fmi2LastSuccessfulTime) {
        LOG_ERROR(inst, "fmi2GetRealStatus: status kind %d is not available.", (int)s);
        return fmi2Discard;
    }
    *value = inst->values.time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Integer *value)
{
    (void)value;
    Instance *inst = checked_cs(c, "fmi2GetIntegerStatus", CS_STATUS_STATES);
    if (inst == NULL) return fmi2Error;
    LOG_ERROR(inst, "fmi2GetIntegerStatus: status kind %d is not available.", (int)s);
    return fmi2Discard;
}

FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Boolean *value)
{
    Instance *inst = checked_cs(c, "fmi2GetBooleanStatus", CS_STATUS_STATES);
    if (inst == NULL) return fmi2Error;
    if (value == NULL) {
        LOG_ERROR(inst, "fmi2GetBooleanStatus: argument value is NULL.");
        return fmi2Error;
    }
    if (s != fmi2Terminated) {
        LOG_ERROR(inst, "fmi2GetBooleanStatus: status kind %d is not available.", (int)s);
        return fmi2Discard;
    }
    *value = fmi2False; /* the model never asks to stop */
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s,
                                           fmi2String *value)
{
    (void)value;
    Instance *inst = checked_cs(c, "fmi2GetStringStatus", CS_STATUS_STATES);
    if (inst == NULL) return fmi2Error;
    LOG_ERROR(inst, "fmi2GetStringStatus: status kind %d is not available.", (int)s);
    return fmi2Discard;
}

#endif /* FLEXSAT_CO_SIMULATION */
