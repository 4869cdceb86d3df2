/* flexsat FMU template: the FMI 3.0 API layer (Model Exchange and Co-Simulation).
 *
 * The FMI 3.0 counterpart of fmi2Functions.c, over the same model code: the values,
 * stepping, FMU states and partial derivatives are in lti_instance.c, the arithmetic in
 * linear_model.c, the system's matrices in the generated model.c.  This file checks every
 * call (instance pointer, state machine, value references, array sizes, null arrays,
 * non-finite numbers), logs what went wrong and returns fmi3Error or fmi3Discard instead
 * of crashing.
 *
 * As FMI 3.0 requires (section 2.5), the library defines every function of
 * fmi3Functions.h; those of interfaces or capabilities this FMU does not declare log an
 * error and return fmi3Error.  Only Float64 variables (and, for a sampled model, its sample
 * clock) exist.  Logging follows section 2.3.1: nothing is logged unless the instance was
 * created with loggingOn = fmi3True (or fmi3SetDebugLogging enabled it).
 *
 * Sampled (discrete-time) models, Co-Simulation only: the model equations form one clocked
 * partition of a periodic time-based input Clock (intervalVariability = "constant",
 * intervalDecimal = T).  An importer in Event Mode activates it at each tick with
 * fmi3SetClock; outputs read then are C x_k + D u_k, and fmi3UpdateDiscreteStates takes the
 * sample (x_{k+1} = A x_k + B u_k).  Ticks that the importer did not activate - an importer
 * without Event Mode (eventModeUsed = fmi3False), or one that does not handle clocks - are
 * taken by fmi3DoStep itself, with the inputs held, so the result is the same.
 *
 * Reference: FMI 3.0.2 standard (Modelica Association, 2024), sections 2.2 (common
 * mechanisms, clocks), 2.3 (common states and functions), 3 (Model Exchange), 4
 * (Co-Simulation).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "flexsat_interfaces.h"
#include "linear_model.h"
#include "lti_instance.h"

#if !FLEXSAT_MODEL_EXCHANGE && !FLEXSAT_CO_SIMULATION
#error "flexsat_interfaces.h must enable FLEXSAT_MODEL_EXCHANGE or FLEXSAT_CO_SIMULATION"
#endif

#define INSTANCE_MAGIC 0x464c5833u /* "FLX3": detects stale or foreign handles */

typedef enum {
    STATE_INSTANTIATED = 1 << 0,
    STATE_INITIALIZATION = 1 << 1,
    STATE_EVENT = 1 << 2,
    STATE_CONTINUOUS = 1 << 3,
    STATE_STEP = 1 << 4,
    STATE_TERMINATED = 1 << 5
} ModelState;

#define ANY_STATE 0xFFFF
#define INITIALIZED (STATE_EVENT | STATE_CONTINUOUS | STATE_STEP)
#define READABLE (STATE_INITIALIZATION | INITIALIZED | STATE_TERMINATED)

#define LOG_ERRORS 1
#define LOG_WARNINGS 2

typedef enum { KIND_MODEL_EXCHANGE, KIND_CO_SIMULATION } InstanceKind;

typedef struct Instance {
    LiNode node; /* first member: the list of live instances */
    unsigned magic;
    InstanceKind kind;
    char *instance_name;
    fmi3LogMessageCallback logger;
    fmi3InstanceEnvironment environment;
    int log_categories; /* LOG_ERRORS | LOG_WARNINGS: what may be logged */
    int event_mode_used;
    int clock_active;   /* the sample clock, activated in Event Mode */
    ModelState state;
    LiValues values;
} Instance;

static const LinearModel *const model = &linear_model;

static size_t n_st(void) { return model->n_states; }
static size_t n_in(void) { return model->n_inputs; }
static size_t n_out(void) { return model->n_outputs; }

static void *allocate_zeroed(size_t count, size_t size) { return calloc(count, size); }

/* ---------------------------------------------------------------- logging */

static void log_message(Instance *inst, fmi3Status status, const char *format, ...)
{
    char text[512];
    va_list args;
    if (inst == NULL || inst->logger == NULL) return;
    const int category = status >= fmi3Error ? LOG_ERRORS : LOG_WARNINGS;
    if (!(inst->log_categories & category)) return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    /* FMI 3.0 passes the message as it is (no printf format): nothing to escape */
    inst->logger(inst->environment, status,
                 category == LOG_ERRORS ? "logStatusError" : "logStatusWarning", text);
}

#define LOG_ERROR(inst, ...) log_message((inst), fmi3Error, __VA_ARGS__)

/* ---------------------------------------------------------------- checks */

static Instance *as_instance(fmi3Instance instance)
{
    Instance *inst = (Instance *)li_find(instance, 0);
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
    case STATE_STEP: return "StepMode";
    case STATE_TERMINATED: return "Terminated";
    }
    return "unknown";
}

/* The instance if the call is allowed in its current state, else NULL (logged). */
static Instance *checked(fmi3Instance instance, const char *function, int allowed_states)
{
    Instance *inst = as_instance(instance);
    if (inst == NULL) return NULL;
    if (!(inst->state & allowed_states)) {
        LOG_ERROR(inst, "%s must not be called in state %s.", function, state_name(inst->state));
        return NULL;
    }
    return inst;
}

static Instance *checked_kind(fmi3Instance instance, const char *function, int allowed,
                              InstanceKind kind)
{
    Instance *inst = as_instance(instance);
    if (inst != NULL && inst->kind != kind) {
        LOG_ERROR(inst, "%s is a %s function; this instance is %s.", function,
                  kind == KIND_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation",
                  inst->kind == KIND_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation");
        return NULL;
    }
    return checked(instance, function, allowed);
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

static int null_pointer(Instance *inst, const char *function, const char *argument,
                        const void *pointer)
{
    if (pointer == NULL) {
        LOG_ERROR(inst, "%s: argument %s is NULL.", function, argument);
        return 1;
    }
    return 0;
}

/* Scalar variables only: nValues must equal nValueReferences. */
static int scalar_count(Instance *inst, const char *function, size_t nvr, size_t n_values)
{
    if (n_values != nvr) {
        LOG_ERROR(inst, "%s: nValues must equal nValueReferences (%lu; every variable is a "
                  "scalar); got %lu.", function, (unsigned long)nvr, (unsigned long)n_values);
        return 1;
    }
    return 0;
}

static fmi3Status unsupported(fmi3Instance instance, const char *function, const char *why)
{
    Instance *inst = as_instance(instance);
    LOG_ERROR(inst, "%s is not supported (%s).", function, why);
    return fmi3Error;
}

/* An output or derivative that is not finite: fmi3Discard in Model Exchange, where the
 * integrator can retry with a smaller step, fmi3Error in Co-Simulation, where fmi3DoStep
 * already refused to reach such a state and only the inputs set since can have caused it. */
static fmi3Status overflowed(Instance *inst, const char *function, const char *what,
                             const char *name)
{
    LOG_ERROR(inst, "%s: %s %s is not finite at t = %g s (the linear model overflows for "
              "these states and inputs).", function, what, name, inst->values.time);
    return inst->kind == KIND_MODEL_EXCHANGE ? fmi3Discard : fmi3Error;
}

/* ---------------------------------------------------------------- version, logging */

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

FMI3_Export fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn,
                                           size_t nCategories, const fmi3String categories[])
{
    Instance *inst = checked(instance, "fmi3SetDebugLogging", ANY_STATE);
    if (inst == NULL) return fmi3Error;
    if (nCategories == 0) {
        inst->log_categories = loggingOn ? (LOG_ERRORS | LOG_WARNINGS) : 0;
        return fmi3OK;
    }
    if (null_array(inst, "fmi3SetDebugLogging", "categories", categories, nCategories))
        return fmi3Error;
    int mask = 0;
    for (size_t i = 0; i < nCategories; i++) {
        if (categories[i] != NULL && strcmp(categories[i], "logStatusError") == 0)
            mask |= LOG_ERRORS;
        else if (categories[i] != NULL && strcmp(categories[i], "logStatusWarning") == 0)
            mask |= LOG_WARNINGS;
        else {
            LOG_ERROR(inst, "fmi3SetDebugLogging: unknown log category \"%s\"; expected "
                      "logStatusError or logStatusWarning.",
                      categories[i] == NULL ? "(null)" : categories[i]);
            return fmi3Error;
        }
    }
    if (loggingOn) inst->log_categories |= mask;
    else inst->log_categories &= ~mask;
    return fmi3OK;
}

/* ---------------------------------------------------------------- instances */

/* Release an instance that is not (or no longer) on the live list. */
static void free_instance(Instance *inst)
{
    char *name = inst->instance_name;
    li_free(&inst->values);
    memset(inst, 0, sizeof *inst);
    free(name);
    free(inst);
}

static Instance *instantiate(const char *function, InstanceKind kind, int provided,
                             fmi3String instanceName, fmi3String instantiationToken,
                             fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                             fmi3LogMessageCallback logMessage, int event_mode_used,
                             size_t n_intermediate)
{
    /* a temporary instance lets the error messages below go through the logger */
    Instance report;
    memset(&report, 0, sizeof report);
    report.magic = INSTANCE_MAGIC;
    report.logger = logMessage;
    report.environment = environment;
    report.log_categories = loggingOn ? (LOG_ERRORS | LOG_WARNINGS) : 0;

    if (instanceName == NULL || instanceName[0] == '\0') {
        LOG_ERROR(&report, "%s: instanceName must be a non-empty string.", function);
        return NULL;
    }
    if (instantiationToken == NULL || strcmp(instantiationToken, model->guid) != 0) {
        LOG_ERROR(&report, "%s: wrong instantiationToken %s; this binary is %s with "
                  "instantiationToken %s.", function,
                  instantiationToken == NULL ? "(null)" : instantiationToken, model->model_name,
                  model->guid);
        return NULL;
    }
    if (!provided) {
        LOG_ERROR(&report, "%s: this FMU does not provide %s (see modelDescription.xml).",
                  function, kind == KIND_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation");
        return NULL;
    }
    if (event_mode_used && !li_discrete()) {
        LOG_ERROR(&report, "%s: eventModeUsed must be fmi3False: this FMU has no events "
                  "(hasEventMode = \"false\").", function);
        return NULL;
    }
    if (n_intermediate > 0) {
        LOG_ERROR(&report, "%s: nRequiredIntermediateVariables must be 0: this FMU provides no "
                  "intermediate update; got %lu.", function, (unsigned long)n_intermediate);
        return NULL;
    }
    Instance *inst = (Instance *)calloc(1, sizeof(Instance));
    if (inst == NULL) {
        LOG_ERROR(&report, "%s: out of memory.", function);
        return NULL;
    }
    inst->magic = INSTANCE_MAGIC;
    inst->kind = kind;
    inst->logger = logMessage;
    inst->environment = environment;
    inst->log_categories = report.log_categories;
    inst->event_mode_used = event_mode_used;
    inst->state = STATE_INSTANTIATED;
    inst->instance_name = (char *)calloc(strlen(instanceName) + 1, 1);
    if (inst->instance_name == NULL
        || li_allocate(&inst->values, allocate_zeroed, free, kind == KIND_CO_SIMULATION) != 0) {
        LOG_ERROR(&report, "%s: out of memory.", function);
        free_instance(inst);
        return NULL;
    }
    strcpy(inst->instance_name, instanceName);
    li_register(&inst->node);
    return inst;
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage)
{
    (void)resourcePath;
    (void)visible;
    return instantiate("fmi3InstantiateModelExchange", KIND_MODEL_EXCHANGE,
                       FLEXSAT_MODEL_EXCHANGE && !li_discrete(), instanceName,
                       instantiationToken, loggingOn, instanceEnvironment, logMessage, 0, 0);
}

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed; /* fmi3DoStep never returns early */
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    return instantiate("fmi3InstantiateCoSimulation", KIND_CO_SIMULATION,
                       FLEXSAT_CO_SIMULATION, instanceName, instantiationToken, loggingOn,
                       instanceEnvironment, logMessage, eventModeUsed ? 1 : 0,
                       nRequiredIntermediateVariables);
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    Instance report;
    memset(&report, 0, sizeof report);
    report.logger = logMessage;
    report.environment = instanceEnvironment;
    report.log_categories = loggingOn ? LOG_ERRORS : 0;
    LOG_ERROR(&report, "fmi3InstantiateScheduledExecution: this FMU does not provide "
              "Scheduled Execution (see modelDescription.xml).");
    return NULL;
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance)
{
    /* taken off the live list first: a second call with the same handle finds nothing */
    Instance *inst = (Instance *)li_find(instance, 1);
    if (inst != NULL) free_instance(inst);
}

/* ---------------------------------------------------------------- initialisation, modes */

FMI3_Export fmi3Status fmi3EnterInitializationMode(fmi3Instance instance,
                                                   fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance,
                                                   fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined,
                                                   fmi3Float64 stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    Instance *inst = checked(instance, "fmi3EnterInitializationMode", STATE_INSTANTIATED);
    if (inst == NULL) return fmi3Error;
    if (!isfinite(startTime)) {
        LOG_ERROR(inst, "fmi3EnterInitializationMode: startTime must be finite [s]; got %g.",
                  startTime);
        return fmi3Error;
    }
    if (stopTimeDefined && !(stopTime >= startTime)) {
        LOG_ERROR(inst, "fmi3EnterInitializationMode: stopTime must be >= startTime [s]; got "
                  "%g < %g.", stopTime, startTime);
        return fmi3Error;
    }
    li_start(&inst->values, startTime);
    inst->state = STATE_INITIALIZATION;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Instance *inst = checked(instance, "fmi3ExitInitializationMode", STATE_INITIALIZATION);
    if (inst == NULL) return fmi3Error;
    if (inst->kind == KIND_MODEL_EXCHANGE || inst->event_mode_used) inst->state = STATE_EVENT;
    else inst->state = STATE_STEP;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    Instance *inst = checked(instance, "fmi3EnterEventMode",
                             STATE_EVENT | STATE_CONTINUOUS | STATE_STEP);
    if (inst == NULL) return fmi3Error;
    if (inst->kind == KIND_CO_SIMULATION && !inst->event_mode_used) {
        LOG_ERROR(inst, "fmi3EnterEventMode must not be called: the instance was created with "
                  "eventModeUsed = fmi3False.");
        return fmi3Error;
    }
    inst->state = STATE_EVENT;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3Terminate(fmi3Instance instance)
{
    Instance *inst = checked(instance, "fmi3Terminate", INITIALIZED);
    if (inst == NULL) return fmi3Error;
    inst->state = STATE_TERMINATED;
    inst->clock_active = 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3Reset(fmi3Instance instance)
{
    Instance *inst = checked(instance, "fmi3Reset", ANY_STATE);
    if (inst == NULL) return fmi3Error;
    li_reset(&inst->values);
    inst->clock_active = 0;
    inst->state = STATE_INSTANTIATED;
    return fmi3OK;
}

/* ---------------------------------------------------------------- variable access */

/* Float64 variables: inputs, outputs, states, derivatives and the time. */
FMI3_Export fmi3Status fmi3GetFloat64(fmi3Instance instance,
                                      const fmi3ValueReference valueReferences[],
                                      size_t nValueReferences, fmi3Float64 values[],
                                      size_t nValues)
{
    static const char *const function = "fmi3GetFloat64";
    Instance *inst = checked(instance, function, STATE_INSTANTIATED | READABLE);
    if (inst == NULL) return fmi3Error;
    if (null_array(inst, function, "valueReferences", valueReferences, nValueReferences)
        || null_array(inst, function, "values", values, nValues)
        || scalar_count(inst, function, nValueReferences, nValues))
        return fmi3Error;
    /* outputs and derivatives from the current inputs: direct feedthrough is never stale */
    LiValues *v = &inst->values;
    li_update_outputs(v);
    if (!li_discrete()) li_update_derivatives(v);
    for (size_t i = 0; i < nValueReferences; i++) {
        size_t k;
        switch (li_kind(valueReferences[i], &k)) {
        case LI_INPUT: values[i] = v->u[k]; break;
        case LI_OUTPUT: values[i] = v->y[k]; break;
        case LI_STATE: values[i] = v->x[k]; break;
        case LI_DERIVATIVE: values[i] = v->dx[k]; break;
        case LI_TIME: values[i] = v->time; break;
        case LI_CLOCK:
            LOG_ERROR(inst, "%s: value reference %u is the sample clock; use fmi3GetClock.",
                      function, (unsigned)valueReferences[i]);
            return fmi3Error;
        default:
            LOG_ERROR(inst, "%s: unknown value reference %u.", function,
                      (unsigned)valueReferences[i]);
            return fmi3Error;
        }
    }
    for (size_t i = 0; i < nValueReferences; i++) {
        size_t k;
        const LiKind kind = li_kind(valueReferences[i], &k);
        if ((kind == LI_OUTPUT || kind == LI_DERIVATIVE) && !isfinite(values[i]))
            return overflowed(inst, function,
                              kind == LI_OUTPUT ? "output" : "derivative of state",
                              kind == LI_OUTPUT ? model->output_names[k]
                                                : model->state_names[k]);
    }
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SetFloat64(fmi3Instance instance,
                                      const fmi3ValueReference valueReferences[],
                                      size_t nValueReferences, const fmi3Float64 values[],
                                      size_t nValues)
{
    static const char *const function = "fmi3SetFloat64";
    Instance *inst = checked(instance, function,
                             STATE_INSTANTIATED | STATE_INITIALIZATION | INITIALIZED);
    if (inst == NULL) return fmi3Error;
    if (null_array(inst, function, "valueReferences", valueReferences, nValueReferences)
        || null_array(inst, function, "values", values, nValues)
        || scalar_count(inst, function, nValueReferences, nValues))
        return fmi3Error;
    const int before_init = inst->state & (STATE_INSTANTIATED | STATE_INITIALIZATION);
    /* check everything first so that a rejected call changes nothing */
    for (size_t i = 0; i < nValueReferences; i++) {
        size_t k;
        const LiKind kind = li_kind(valueReferences[i], &k);
        if (kind == LI_INVALID || kind == LI_CLOCK) {
            LOG_ERROR(inst, "%s: %s value reference %u.", function,
                      kind == LI_CLOCK ? "not a Float64 variable: the sample clock," : "unknown",
                      (unsigned)valueReferences[i]);
            return fmi3Error;
        }
        if (kind == LI_OUTPUT || kind == LI_DERIVATIVE || kind == LI_TIME) {
            LOG_ERROR(inst, "%s: %s is calculated and cannot be set.", function,
                      kind == LI_OUTPUT ? model->output_names[k]
                      : kind == LI_TIME ? "the time (the independent variable)"
                                        : "a state derivative");
            return fmi3Error;
        }
        if (kind == LI_STATE && !before_init) {
            LOG_ERROR(inst, "%s: state %s can only be set before initialisation is finished "
                      "(use fmi3SetContinuousStates in Model Exchange).", function,
                      model->state_names[k]);
            return fmi3Error;
        }
        if (!isfinite(values[i])) {
            LOG_ERROR(inst, "%s: %s %s must be finite; got %g. The value was not set.",
                      function, kind == LI_INPUT ? "input" : "state",
                      kind == LI_INPUT ? model->input_names[k] : model->state_names[k],
                      values[i]);
            return fmi3Error;
        }
    }
    for (size_t i = 0; i < nValueReferences; i++) {
        size_t k = 0;
        if (li_kind(valueReferences[i], &k) == LI_INPUT) inst->values.u[k] = values[i];
        else inst->values.x[k] = values[i];
    }
    return fmi3OK;
}

/* This model has no variables of the other types. */
static fmi3Status no_such_variables(fmi3Instance instance, const char *function,
                                    const fmi3ValueReference vr[], size_t nvr)
{
    Instance *inst = checked(instance, function, ANY_STATE);
    if (inst == NULL) return fmi3Error;
    if (nvr > 0) {
        LOG_ERROR(inst, "%s: unknown value reference %u (this model has only Float64 "
                  "variables%s).", function, vr == NULL ? 0u : (unsigned)vr[0],
                  li_discrete() ? " and a Clock" : "");
        return fmi3Error;
    }
    return fmi3OK;
}

#define NO_SUCH_GETTER(NAME, TYPE)                                                         \
    FMI3_Export fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[],     \
                                size_t nvr, TYPE values[], size_t nValues)                 \
    {                                                                                      \
        (void)values;                                                                      \
        (void)nValues;                                                                     \
        return no_such_variables(instance, #NAME, vr, nvr);                                \
    }
#define NO_SUCH_SETTER(NAME, TYPE)                                                         \
    FMI3_Export fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[],     \
                                size_t nvr, const TYPE values[], size_t nValues)           \
    {                                                                                      \
        (void)values;                                                                      \
        (void)nValues;                                                                     \
        return no_such_variables(instance, #NAME, vr, nvr);                                \
    }

NO_SUCH_GETTER(fmi3GetFloat32, fmi3Float32)
NO_SUCH_GETTER(fmi3GetInt8, fmi3Int8)
NO_SUCH_GETTER(fmi3GetUInt8, fmi3UInt8)
NO_SUCH_GETTER(fmi3GetInt16, fmi3Int16)
NO_SUCH_GETTER(fmi3GetUInt16, fmi3UInt16)
NO_SUCH_GETTER(fmi3GetInt32, fmi3Int32)
NO_SUCH_GETTER(fmi3GetUInt32, fmi3UInt32)
NO_SUCH_GETTER(fmi3GetInt64, fmi3Int64)
NO_SUCH_GETTER(fmi3GetUInt64, fmi3UInt64)
NO_SUCH_GETTER(fmi3GetBoolean, fmi3Boolean)
NO_SUCH_GETTER(fmi3GetString, fmi3String)
NO_SUCH_SETTER(fmi3SetFloat32, fmi3Float32)
NO_SUCH_SETTER(fmi3SetInt8, fmi3Int8)
NO_SUCH_SETTER(fmi3SetUInt8, fmi3UInt8)
NO_SUCH_SETTER(fmi3SetInt16, fmi3Int16)
NO_SUCH_SETTER(fmi3SetUInt16, fmi3UInt16)
NO_SUCH_SETTER(fmi3SetInt32, fmi3Int32)
NO_SUCH_SETTER(fmi3SetUInt32, fmi3UInt32)
NO_SUCH_SETTER(fmi3SetInt64, fmi3Int64)
NO_SUCH_SETTER(fmi3SetUInt64, fmi3UInt64)
NO_SUCH_SETTER(fmi3SetBoolean, fmi3Boolean)
NO_SUCH_SETTER(fmi3SetString, fmi3String)

FMI3_Export fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[],
                                     size_t nvr, size_t valueSizes[], fmi3Binary values[],
                                     size_t nValues)
{
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_such_variables(instance, "fmi3GetBinary", vr, nvr);
}

FMI3_Export fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[],
                                     size_t nvr, const size_t valueSizes[],
                                     const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_such_variables(instance, "fmi3SetBinary", vr, nvr);
}

/* ---------------------------------------------------------------- clocks */

/* Every value reference must be the sample clock (sampled models only). */
static int only_the_clock(Instance *inst, const char *function, const fmi3ValueReference vr[],
                          size_t nvr)
{
    if (null_array(inst, function, "valueReferences", vr, nvr)) return 0;
    for (size_t i = 0; i < nvr; i++) {
        size_t k;
        if (li_kind(vr[i], &k) != LI_CLOCK) {
            LOG_ERROR(inst, "%s: value reference %u is not a Clock%s.", function,
                      (unsigned)vr[i], li_discrete() ? " (only the sample clock is)"
                                                     : " (this model has none)");
            return 0;
        }
    }
    return 1;
}

FMI3_Export fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, fmi3Clock values[])
{
    Instance *inst = checked(instance, "fmi3GetClock", ANY_STATE);
    if (inst == NULL) return fmi3Error;
    if (!only_the_clock(inst, "fmi3GetClock", vr, nvr)
        || null_array(inst, "fmi3GetClock", "values", values, nvr))
        return fmi3Error;
    for (size_t i = 0; i < nvr; i++) values[i] = inst->clock_active ? fmi3ClockActive
                                                                    : fmi3ClockInactive;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Clock values[])
{
    static const char *const function = "fmi3SetClock";
    Instance *inst = checked(instance, function, STATE_EVENT);
    if (inst == NULL) return fmi3Error;
    if (!only_the_clock(inst, function, vr, nvr) || null_array(inst, function, "values", values, nvr))
        return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        if (values[i] && !li_sample_pending(&inst->values)) {
            LOG_ERROR(inst, "%s: the sample clock ticks at %.17g s (every %g s); it cannot be "
                      "activated at t = %.17g s.", function,
                      li_next_sample_time(&inst->values), model->sample_period,
                      inst->values.time);
            return fmi3Error;
        }
    }
    for (size_t i = 0; i < nvr; i++) inst->clock_active = values[i] ? 1 : 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance,
                                              const fmi3ValueReference vr[], size_t nvr,
                                              fmi3Float64 intervals[],
                                              fmi3IntervalQualifier qualifiers[])
{
    static const char *const function = "fmi3GetIntervalDecimal";
    Instance *inst = checked(instance, function, ANY_STATE);
    if (inst == NULL) return fmi3Error;
    if (!only_the_clock(inst, function, vr, nvr)
        || null_array(inst, function, "intervals", intervals, nvr)
        || null_array(inst, function, "qualifiers", qualifiers, nvr))
        return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        intervals[i] = model->sample_period;
        qualifiers[i] = fmi3IntervalUnchanged; /* constant: as in modelDescription.xml */
    }
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                           size_t nvr, fmi3Float64 shifts[])
{
    static const char *const function = "fmi3GetShiftDecimal";
    Instance *inst = checked(instance, function, ANY_STATE);
    if (inst == NULL) return fmi3Error;
    if (!only_the_clock(inst, function, vr, nvr) || null_array(inst, function, "shifts", shifts, nvr))
        return fmi3Error;
    for (size_t i = 0; i < nvr; i++) shifts[i] = 0.0; /* first tick at the start time */
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetIntervalFraction(fmi3Instance instance,
                                               const fmi3ValueReference vr[], size_t nvr,
                                               fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                               fmi3IntervalQualifier qualifiers[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalFraction", "supportsFraction=\"false\"");
}

FMI3_Export fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                            size_t nvr, fmi3UInt64 counters[],
                                            fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, "fmi3GetShiftFraction", "supportsFraction=\"false\"");
}

FMI3_Export fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance,
                                              const fmi3ValueReference vr[], size_t nvr,
                                              const fmi3Float64 intervals[])
{
    (void)vr;
    (void)nvr;
    (void)intervals;
    return unsupported(instance, "fmi3SetIntervalDecimal",
                       "the sample clock's interval is constant");
}

FMI3_Export fmi3Status fmi3SetIntervalFraction(fmi3Instance instance,
                                               const fmi3ValueReference vr[], size_t nvr,
                                               const fmi3UInt64 counters[],
                                               const fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, "fmi3SetIntervalFraction",
                       "the sample clock's interval is constant");
}

FMI3_Export fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                           size_t nvr, const fmi3Float64 shifts[])
{
    (void)vr;
    (void)nvr;
    (void)shifts;
    return unsupported(instance, "fmi3SetShiftDecimal", "the sample clock's shift is constant");
}

FMI3_Export fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                            size_t nvr, const fmi3UInt64 counters[],
                                            const fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, "fmi3SetShiftFraction", "the sample clock's shift is constant");
}

FMI3_Export fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EvaluateDiscreteStates",
                       "providesEvaluateDiscreteStates=\"false\"");
}

FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance,
                                                fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined,
                                                fmi3Float64 *nextEventTime)
{
    static const char *const function = "fmi3UpdateDiscreteStates";
    Instance *inst = checked(instance, function, STATE_EVENT);
    if (inst == NULL) return fmi3Error;
    if (null_pointer(inst, function, "discreteStatesNeedUpdate", discreteStatesNeedUpdate)
        || null_pointer(inst, function, "terminateSimulation", terminateSimulation)
        || null_pointer(inst, function, "nominalsOfContinuousStatesChanged",
                        nominalsOfContinuousStatesChanged)
        || null_pointer(inst, function, "valuesOfContinuousStatesChanged",
                        valuesOfContinuousStatesChanged)
        || null_pointer(inst, function, "nextEventTimeDefined", nextEventTimeDefined)
        || null_pointer(inst, function, "nextEventTime", nextEventTime))
        return fmi3Error;
    if (inst->clock_active) {
        /* the clocked partition: y_k = C x_k + D u_k held, x_k+1 = A x_k + B u_k */
        size_t index;
        const int status = li_sample_now(&inst->values, &index);
        inst->clock_active = 0;
        if (status != LI_OK) {
            LOG_ERROR(inst, "%s: the sample at t = %g s overflowed (%s %s); nothing was "
                      "changed.", function, inst->values.time,
                      status == LI_OUTPUT_OVERFLOW ? "output" : "state",
                      status == LI_OUTPUT_OVERFLOW ? model->output_names[index]
                                                   : model->state_names[index]);
            return fmi3Error;
        }
    }
    /* a linear time-invariant system has no other events */
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0.0;
    return fmi3OK;
}

/* ---------------------------------------------------------------- dependencies */

/* The dependencies of an output or derivative: states and inputs with a nonzero entry of
 * [[A, B], [C, D]] (discrete time: inputs with D != 0), as in modelDescription.xml. */
static size_t dependencies(const Instance *inst, LiKind kind, size_t row,
                           fmi3ValueReference independents[])
{
    size_t count = 0;
    const unsigned long first_state = (unsigned long)(n_in() + n_out());
    LiValues probe = inst->values;
    /* discrete time: the structure, not the value between samples */
    probe.time = li_next_sample_time(&inst->values);
    if (li_is_known(LI_STATE)) {
        for (size_t j = 0; j < n_st(); j++) {
            if (li_partial(&probe, kind, row, LI_STATE, j) != 0.0) {
                if (independents != NULL) independents[count] = (fmi3ValueReference)(first_state + j);
                count++;
            }
        }
    }
    for (size_t k = 0; k < n_in(); k++) {
        if (li_partial(&probe, kind, row, LI_INPUT, k) != 0.0) {
            if (independents != NULL) independents[count] = (fmi3ValueReference)k;
            count++;
        }
    }
    return count;
}

static int dependent_of(Instance *inst, const char *function, fmi3ValueReference vr,
                        LiKind *kind, size_t *row)
{
    *kind = li_kind(vr, row);
    if (!li_is_unknown(*kind)) {
        LOG_ERROR(inst, "%s: value reference %u is not an output%s.", function, (unsigned)vr,
                  li_discrete() ? "" : " or a state derivative");
        return 0;
    }
    return 1;
}

FMI3_Export fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                                           fmi3ValueReference valueReference,
                                                           size_t *nDependencies)
{
    static const char *const function = "fmi3GetNumberOfVariableDependencies";
    Instance *inst = checked(instance, function, STATE_INSTANTIATED | READABLE);
    LiKind kind;
    size_t row;
    if (inst == NULL || null_pointer(inst, function, "nDependencies", nDependencies)
        || !dependent_of(inst, function, valueReference, &kind, &row))
        return fmi3Error;
    *nDependencies = dependencies(inst, kind, row, NULL);
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetVariableDependencies(fmi3Instance instance,
                                                   fmi3ValueReference dependent,
                                                   size_t elementIndicesOfDependent[],
                                                   fmi3ValueReference independents[],
                                                   size_t elementIndicesOfIndependents[],
                                                   fmi3DependencyKind dependencyKinds[],
                                                   size_t nDependencies)
{
    static const char *const function = "fmi3GetVariableDependencies";
    Instance *inst = checked(instance, function, STATE_INSTANTIATED | READABLE);
    LiKind kind;
    size_t row;
    if (inst == NULL || !dependent_of(inst, function, dependent, &kind, &row)) return fmi3Error;
    const size_t count = dependencies(inst, kind, row, NULL);
    if (nDependencies != count) {
        LOG_ERROR(inst, "%s: nDependencies must be %lu (fmi3GetNumberOfVariableDependencies); "
                  "got %lu.", function, (unsigned long)count, (unsigned long)nDependencies);
        return fmi3Error;
    }
    if (null_array(inst, function, "elementIndicesOfDependent", elementIndicesOfDependent, count)
        || null_array(inst, function, "independents", independents, count)
        || null_array(inst, function, "elementIndicesOfIndependents",
                      elementIndicesOfIndependents, count)
        || null_array(inst, function, "dependencyKinds", dependencyKinds, count))
        return fmi3Error;
    (void)dependencies(inst, kind, row, independents);
    for (size_t i = 0; i < count; i++) {
        elementIndicesOfDependent[i] = 0; /* scalars */
        elementIndicesOfIndependents[i] = 0;
        dependencyKinds[i] = fmi3Constant; /* a constant factor: the matrix entry */
    }
    return fmi3OK;
}

/* ---------------------------------------------------------------- FMU states */

/* An FMU state holds the mode too (lti_instance.c), for the kind of instance it was saved
 * by. */
static unsigned kind_code(const Instance *inst) { return inst->kind == KIND_CO_SIMULATION ? 1u : 0u; }

static unsigned valid_modes(const Instance *inst)
{
    const unsigned common = STATE_INSTANTIATED | STATE_INITIALIZATION | STATE_TERMINATED;
    if (inst->kind == KIND_MODEL_EXCHANGE) return common | STATE_EVENT | STATE_CONTINUOUS;
    return common | STATE_STEP | (inst->event_mode_used ? STATE_EVENT : 0u);
}

static LiSnapshot *our_state(Instance *inst, const char *function, fmi3FMUState FMUState)
{
    LiSnapshot *state = li_find_snapshot(&inst->values, FMUState);
    if (state == NULL)
        LOG_ERROR(inst, "%s: FMUState is not a state of this instance (NULL, freed, or "
                  "another instance's).", function);
    return state;
}

FMI3_Export fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    Instance *inst = checked(instance, "fmi3GetFMUState", ANY_STATE);
    if (inst == NULL || null_pointer(inst, "fmi3GetFMUState", "FMUState", FMUState))
        return fmi3Error;
    LiSnapshot *state = (LiSnapshot *)*FMUState;
    const int status = li_save(&inst->values, &state, (unsigned)inst->state, kind_code(inst));
    if (status == -2) {
        LOG_ERROR(inst, "fmi3GetFMUState: *FMUState must be NULL (a new state) or a state of "
                  "this instance to overwrite; got another pointer.");
        return fmi3Error;
    }
    if (status != 0) {
        LOG_ERROR(inst, "fmi3GetFMUState: out of memory.");
        return fmi3Error;
    }
    *FMUState = state;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    Instance *inst = checked(instance, "fmi3SetFMUState", ANY_STATE);
    if (inst == NULL) return fmi3Error;
    LiSnapshot *state = our_state(inst, "fmi3SetFMUState", FMUState);
    if (state == NULL) return fmi3Error;
    li_restore(&inst->values, state);
    inst->state = (ModelState)li_snapshot_mode(state); /* the mode is part of the state */
    inst->clock_active = 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    Instance *inst = checked(instance, "fmi3FreeFMUState", ANY_STATE);
    if (inst == NULL || null_pointer(inst, "fmi3FreeFMUState", "FMUState", FMUState))
        return fmi3Error;
    if (*FMUState == NULL) return fmi3OK; /* nothing to free */
    if (li_discard(&inst->values, (LiSnapshot *)*FMUState) != 0) {
        LOG_ERROR(inst, "fmi3FreeFMUState: *FMUState is not a state of this instance (freed "
                  "already, or another instance's).");
        return fmi3Error;
    }
    *FMUState = NULL;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                                  size_t *size)
{
    Instance *inst = checked(instance, "fmi3SerializedFMUStateSize", ANY_STATE);
    if (inst == NULL || our_state(inst, "fmi3SerializedFMUStateSize", FMUState) == NULL
        || null_pointer(inst, "fmi3SerializedFMUStateSize", "size", size))
        return fmi3Error;
    *size = li_serialized_size();
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                             fmi3Byte serializedState[], size_t size)
{
    static const char *const function = "fmi3SerializeFMUState";
    Instance *inst = checked(instance, function, ANY_STATE);
    if (inst == NULL) return fmi3Error;
    LiSnapshot *state = our_state(inst, function, FMUState);
    if (state == NULL || null_array(inst, function, "serializedState", serializedState, size))
        return fmi3Error;
    if (size < li_serialized_size()) {
        LOG_ERROR(inst, "%s: size must be at least %lu bytes (see fmi3SerializedFMUStateSize); "
                  "got %lu.", function, (unsigned long)li_serialized_size(), (unsigned long)size);
        return fmi3Error;
    }
    li_serialize(state, serializedState);
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3DeserializeFMUState(fmi3Instance instance,
                                               const fmi3Byte serializedState[], size_t size,
                                               fmi3FMUState *FMUState)
{
    static const char *const function = "fmi3DeserializeFMUState";
    Instance *inst = checked(instance, function, ANY_STATE);
    if (inst == NULL || null_pointer(inst, function, "FMUState", FMUState)
        || null_array(inst, function, "serializedState", serializedState, size))
        return fmi3Error;
    LiSnapshot *state = (LiSnapshot *)*FMUState;
    const char *why = NULL;
    if (li_deserialize(&inst->values, serializedState, size, kind_code(inst), valid_modes(inst),
                       &state, &why) != 0) {
        LOG_ERROR(inst, "%s: the %lu bytes are not a serialized state of this model: %s.",
                  function, (unsigned long)size, why != NULL ? why : "out of memory");
        return fmi3Error;
    }
    *FMUState = state;
    return fmi3OK;
}

/* ---------------------------------------------------------------- partial derivatives */

static int check_partials(Instance *inst, const char *function,
                          const fmi3ValueReference unknowns[], size_t nUnknowns,
                          const fmi3ValueReference knowns[], size_t nKnowns,
                          const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                          size_t nSensitivity, size_t expected_seed, size_t expected_sensitivity)
{
    if (null_array(inst, function, "unknowns", unknowns, nUnknowns)
        || null_array(inst, function, "knowns", knowns, nKnowns)
        || null_array(inst, function, "seed", seed, nSeed)
        || null_array(inst, function, "sensitivity", sensitivity, nSensitivity))
        return 0;
    if (nSeed != expected_seed || nSensitivity != expected_sensitivity) {
        LOG_ERROR(inst, "%s: nSeed must be %lu and nSensitivity %lu (every variable is a "
                  "scalar); got %lu and %lu.", function, (unsigned long)expected_seed,
                  (unsigned long)expected_sensitivity, (unsigned long)nSeed,
                  (unsigned long)nSensitivity);
        return 0;
    }
    for (size_t k = 0; k < nSeed; k++) {
        if (!isfinite(seed[k])) {
            LOG_ERROR(inst, "%s: seed[%lu] must be finite; got %g.", function, (unsigned long)k,
                      seed[k]);
            return 0;
        }
    }
    for (size_t i = 0; i < nUnknowns; i++) {
        size_t row;
        if (!li_is_unknown(li_kind(unknowns[i], &row))) {
            LOG_ERROR(inst, "%s: value reference %u is not an unknown of this model (%s).",
                      function, (unsigned)unknowns[i],
                      li_discrete() ? "an output" : "an output or a state derivative");
            return 0;
        }
    }
    for (size_t k = 0; k < nKnowns; k++) {
        size_t column;
        if (!li_is_known(li_kind(knowns[k], &column))) {
            LOG_ERROR(inst, "%s: value reference %u is not a known of this model (%s).",
                      function, (unsigned)knowns[k],
                      li_discrete() ? "an input" : "an input or a state");
            return 0;
        }
    }
    return 1;
}

/* sensitivity = J seed (directional) or J^T seed (adjoint), J the block of
 * [[A, B], [C, D]] (lti_instance.h).  One loop for both: each sensitivity accumulates its
 * terms in the order of the seed's entries. */
static void partials(Instance *inst, const fmi3ValueReference unknowns[], size_t nUnknowns,
                     const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                     fmi3Float64 sensitivity[], int adjoint)
{
    const size_t n_sensitivity = adjoint ? nKnowns : nUnknowns;
    for (size_t o = 0; o < n_sensitivity; o++) sensitivity[o] = 0.0;
    for (size_t i = 0; i < nUnknowns; i++) {
        size_t row, column;
        const LiKind unknown = li_kind(unknowns[i], &row);
        for (size_t k = 0; k < nKnowns; k++) {
            const LiKind known = li_kind(knowns[k], &column);
            const double entry = li_partial(&inst->values, unknown, row, known, column);
            if (adjoint) sensitivity[k] += entry * seed[i];
            else sensitivity[i] += entry * seed[k];
        }
    }
}

FMI3_Export fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance,
                                                    const fmi3ValueReference unknowns[],
                                                    size_t nUnknowns,
                                                    const fmi3ValueReference knowns[],
                                                    size_t nKnowns, const fmi3Float64 seed[],
                                                    size_t nSeed, fmi3Float64 sensitivity[],
                                                    size_t nSensitivity)
{
    static const char *const function = "fmi3GetDirectionalDerivative";
    Instance *inst = checked(instance, function, READABLE);
    if (inst == NULL
        || !check_partials(inst, function, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                           sensitivity, nSensitivity, nKnowns, nUnknowns))
        return fmi3Error;
    partials(inst, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity, 0);
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance,
                                                const fmi3ValueReference unknowns[],
                                                size_t nUnknowns,
                                                const fmi3ValueReference knowns[],
                                                size_t nKnowns, const fmi3Float64 seed[],
                                                size_t nSeed, fmi3Float64 sensitivity[],
                                                size_t nSensitivity)
{
    static const char *const function = "fmi3GetAdjointDerivative";
    Instance *inst = checked(instance, function, READABLE);
    if (inst == NULL
        || !check_partials(inst, function, unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                           sensitivity, nSensitivity, nUnknowns, nKnowns))
        return fmi3Error;
    partials(inst, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity, 1);
    return fmi3OK;
}

/* ---------------------------------------------------------------- configuration mode */

FMI3_Export fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterConfigurationMode",
                       "this model has no structural parameters");
}

FMI3_Export fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3ExitConfigurationMode",
                       "this model has no structural parameters");
}

/* ---------------------------------------------------------------- Model Exchange */

#define ME_READABLE (STATE_INITIALIZATION | STATE_EVENT | STATE_CONTINUOUS | STATE_TERMINATED)

static Instance *checked_me(fmi3Instance instance, const char *function, int allowed)
{
    return checked_kind(instance, function, allowed, KIND_MODEL_EXCHANGE);
}

FMI3_Export fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    Instance *inst = checked_me(instance, "fmi3EnterContinuousTimeMode", STATE_EVENT);
    if (inst == NULL) return fmi3Error;
    inst->state = STATE_CONTINUOUS;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                                   fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode,
                                                   fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    static const char *const function = "fmi3CompletedIntegratorStep";
    Instance *inst = checked_me(instance, function, STATE_CONTINUOUS);
    if (inst == NULL || null_pointer(inst, function, "enterEventMode", enterEventMode)
        || null_pointer(inst, function, "terminateSimulation", terminateSimulation))
        return fmi3Error;
    *enterEventMode = fmi3False;
    *terminateSimulation = fmi3False;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    Instance *inst = checked_me(instance, "fmi3SetTime", STATE_EVENT | STATE_CONTINUOUS);
    if (inst == NULL) return fmi3Error;
    if (!isfinite(time)) {
        LOG_ERROR(inst, "fmi3SetTime: time must be finite [s]; got %g.", time);
        return fmi3Error;
    }
    inst->values.time = time;
    return fmi3OK;
}

static int state_count(Instance *inst, const char *function, size_t nx)
{
    if (nx != n_st()) {
        LOG_ERROR(inst, "%s: nContinuousStates must be %lu; got %lu.", function,
                  (unsigned long)n_st(), (unsigned long)nx);
        return 0;
    }
    return 1;
}

FMI3_Export fmi3Status fmi3SetContinuousStates(fmi3Instance instance,
                                               const fmi3Float64 continuousStates[],
                                               size_t nContinuousStates)
{
    static const char *const function = "fmi3SetContinuousStates";
    Instance *inst = checked_me(instance, function, STATE_CONTINUOUS);
    if (inst == NULL || !state_count(inst, function, nContinuousStates)
        || null_array(inst, function, "continuousStates", continuousStates, nContinuousStates))
        return fmi3Error;
    for (size_t i = 0; i < nContinuousStates; i++) {
        if (!isfinite(continuousStates[i])) {
            LOG_ERROR(inst, "%s: state %s must be finite; got %g. No state was set.", function,
                      model->state_names[i], continuousStates[i]);
            return fmi3Error;
        }
    }
    for (size_t i = 0; i < nContinuousStates; i++) inst->values.x[i] = continuousStates[i];
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance,
                                                         fmi3Float64 derivatives[],
                                                         size_t nContinuousStates)
{
    static const char *const function = "fmi3GetContinuousStateDerivatives";
    Instance *inst = checked_me(instance, function, ME_READABLE);
    if (inst == NULL || !state_count(inst, function, nContinuousStates)
        || null_array(inst, function, "derivatives", derivatives, nContinuousStates))
        return fmi3Error;
    li_update_derivatives(&inst->values);
    for (size_t i = 0; i < nContinuousStates; i++) derivatives[i] = inst->values.dx[i];
    for (size_t i = 0; i < nContinuousStates; i++) {
        if (!isfinite(derivatives[i]))
            return overflowed(inst, function, "derivative of state", model->state_names[i]);
    }
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetEventIndicators(fmi3Instance instance,
                                              fmi3Float64 eventIndicators[],
                                              size_t nEventIndicators)
{
    (void)eventIndicators;
    Instance *inst = checked_me(instance, "fmi3GetEventIndicators", ME_READABLE);
    if (inst == NULL) return fmi3Error;
    if (nEventIndicators != 0) {
        LOG_ERROR(inst, "fmi3GetEventIndicators: this model has no event indicators; got "
                  "nEventIndicators = %lu.", (unsigned long)nEventIndicators);
        return fmi3Error;
    }
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetContinuousStates(fmi3Instance instance,
                                               fmi3Float64 continuousStates[],
                                               size_t nContinuousStates)
{
    static const char *const function = "fmi3GetContinuousStates";
    Instance *inst = checked_me(instance, function, ME_READABLE);
    if (inst == NULL || !state_count(inst, function, nContinuousStates)
        || null_array(inst, function, "continuousStates", continuousStates, nContinuousStates))
        return fmi3Error;
    for (size_t i = 0; i < nContinuousStates; i++) continuousStates[i] = inst->values.x[i];
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance,
                                                         fmi3Float64 nominals[],
                                                         size_t nContinuousStates)
{
    static const char *const function = "fmi3GetNominalsOfContinuousStates";
    Instance *inst = checked_me(instance, function, STATE_INSTANTIATED | ME_READABLE);
    if (inst == NULL || !state_count(inst, function, nContinuousStates)
        || null_array(inst, function, "nominals", nominals, nContinuousStates))
        return fmi3Error;
    for (size_t i = 0; i < nContinuousStates; i++) nominals[i] = model->nominals[i];
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance,
                                                      size_t *nEventIndicators)
{
    Instance *inst = checked_me(instance, "fmi3GetNumberOfEventIndicators", ANY_STATE);
    if (inst == NULL
        || null_pointer(inst, "fmi3GetNumberOfEventIndicators", "nEventIndicators",
                        nEventIndicators))
        return fmi3Error;
    *nEventIndicators = 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance,
                                                       size_t *nContinuousStates)
{
    Instance *inst = checked_me(instance, "fmi3GetNumberOfContinuousStates", ANY_STATE);
    if (inst == NULL
        || null_pointer(inst, "fmi3GetNumberOfContinuousStates", "nContinuousStates",
                        nContinuousStates))
        return fmi3Error;
    *nContinuousStates = n_st();
    return fmi3OK;
}

/* ---------------------------------------------------------------- Co-Simulation */

static Instance *checked_cs(fmi3Instance instance, const char *function, int allowed)
{
    return checked_kind(instance, function, allowed, KIND_CO_SIMULATION);
}

FMI3_Export fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    Instance *inst = checked_cs(instance, "fmi3EnterStepMode", STATE_EVENT);
    if (inst == NULL) return fmi3Error;
    inst->clock_active = 0;
    inst->state = STATE_STEP;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance,
                                                const fmi3ValueReference valueReferences[],
                                                size_t nValueReferences,
                                                const fmi3Int32 orders[], fmi3Float64 values[],
                                                size_t nValues)
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    return unsupported(instance, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder = 0");
}

FMI3_Export fmi3Status fmi3DoStep(fmi3Instance instance,
                                  fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize,
                                  fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded,
                                  fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                                  fmi3Float64 *lastSuccessfulTime)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    static const char *const function = "fmi3DoStep";
    Instance *inst = checked_cs(instance, function, STATE_STEP);
    if (inst == NULL || null_pointer(inst, function, "eventHandlingNeeded", eventHandlingNeeded)
        || null_pointer(inst, function, "terminateSimulation", terminateSimulation)
        || null_pointer(inst, function, "earlyReturn", earlyReturn)
        || null_pointer(inst, function, "lastSuccessfulTime", lastSuccessfulTime))
        return fmi3Error;
    const double t = currentCommunicationPoint, h = communicationStepSize;
    const double reached = inst->values.time;
    if (!(h > 0.0) || !isfinite(h)) {
        LOG_ERROR(inst, "%s: communicationStepSize must be positive and finite [s]; got %g.",
                  function, h);
        return fmi3Error;
    }
    if (!isfinite(t) || fabs(t - reached) > 1e-9 * (1.0 + fabs(reached))) {
        LOG_ERROR(inst, "%s: currentCommunicationPoint must equal the time reached so far, "
                  "%.17g s; got %.17g s.", function, reached, t);
        return fmi3Error;
    }
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    size_t index;
    int detail;
    const int status = li_do_step(&inst->values, t, h, &index, &detail);
    *lastSuccessfulTime = inst->values.time;
    switch (status) {
    case LI_OK:
        return fmi3OK;
    case LI_NO_TRANSITION:
        LOG_ERROR(inst, "%s: the transition matrix for the step %g s is not finite (code %d); "
                  "the state was not changed.", function, h, detail);
        break;
    case LI_STATE_OVERFLOW:
        LOG_ERROR(inst, "%s: state %s overflowed at t = %g s; the state was not changed.",
                  function, model->state_names[index], t + h);
        break;
    case LI_OUTPUT_OVERFLOW:
        LOG_ERROR(inst, "%s: output %s overflowed at t = %g s; the state was not changed.",
                  function, model->output_names[index], t + h);
        break;
    default:
        LOG_ERROR(inst, "%s: the step of %g s spans 2^53 or more samples of the sample period "
                  "%g s; the state was not changed.", function, h, model->sample_period);
        break;
    }
    /* the instance stays in Step Mode at lastSuccessfulTime: a shorter step (or a restored
     * FMU state) may follow */
    return fmi3Discard;
}

/* ---------------------------------------------------------------- Scheduled Execution */

FMI3_Export fmi3Status fmi3ActivateModelPartition(fmi3Instance instance,
                                                  fmi3ValueReference clockReference,
                                                  fmi3Float64 activationTime)
{
    (void)clockReference;
    (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition",
                       "this FMU does not provide Scheduled Execution");
}
