/* flexsat FMU template: the FMI 2.0 API layer (Model Exchange and Co-Simulation).
 *
 * One binary serves both interfaces.  This file checks every call (instance pointer, state
 * machine, value references, null arrays, non-finite numbers), logs what went wrong through
 * the environment's logger and returns fmi2Error or fmi2Discard instead of crashing.  The
 * arithmetic is in linear_model.c, the system's matrices in the generated model.c.
 *
 * Which interfaces the library provides is set by the generated flexsat_interfaces.h
 * (FLEXSAT_MODEL_EXCHANGE, FLEXSAT_CO_SIMULATION, as declared in modelDescription.xml): the
 * library exports exactly the fmi2 functions of those interfaces.
 *
 * Instances: every live instance is on a list guarded by a mutex, and each call first
 * looks its fmi2Component up there by address, without dereferencing it.  A stale handle -
 * e.g. a second fmi2FreeInstance, which the standard leaves undefined - is therefore
 * refused without reading freed memory, unless the allocator has since handed the same
 * address to a new instance of this FMU (then the handle is that instance: no handle
 * scheme that returns plain pointers can tell the two apart).  Freed instances are
 * cleared before their memory is released.
 *
 * Value references (fixed layout, the same in modelDescription.xml):
 *     inputs       0 .. m-1
 *     outputs      m .. m+p-1
 *     states       m+p .. m+p+n-1
 *     derivatives  m+p+n .. m+p+2n-1
 *
 * Reference: FMI 2.0.1 standard (Modelica Association, 2019), section 2.1 (common API and
 * state machine), 3.2 (Model Exchange), 4.2 (Co-Simulation).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
#else
#include <pthread.h>
#endif

#include "fmi2Functions.h"
#include "flexsat_interfaces.h"
#include "linear_model.h"

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
    unsigned magic;
    struct Instance *next; /* the list of live instances */
    fmi2Type type;
    char *instance_name;
    fmi2CallbackLogger logger;
    fmi2CallbackFreeMemory free_memory;
    fmi2ComponentEnvironment environment;
    int logging_on;
    ModelState state;
    double time;
    double *x;          /* states, size max(n, 1) */
    double *u;          /* inputs, size max(m, 1) */
    double *y;          /* outputs, size max(p, 1) */
    double *dx;         /* derivatives / next state, size max(n, 1) */
    double *Phi;        /* transition matrices for cached_step */
    double *Gamma;
    double cached_step; /* step of Phi, Gamma; 0 if none */
    double *work;       /* workspace of lm_discretize */
} Instance;

static const LinearModel *const model = &linear_model;

static size_t n_st(void) { return model->n_states; }
static size_t n_in(void) { return model->n_inputs; }
static size_t n_out(void) { return model->n_outputs; }
static size_t at_least_one(size_t k) { return k > 0 ? k : 1; }

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

/* ---------------------------------------------------------------- live instances */

#if defined(_WIN32)
static SRWLOCK registry_lock = SRWLOCK_INIT;
static void lock_registry(void) { AcquireSRWLockExclusive(&registry_lock); }
static void unlock_registry(void) { ReleaseSRWLockExclusive(&registry_lock); }
#else
static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER;
static void lock_registry(void) { pthread_mutex_lock(&registry_lock); }
static void unlock_registry(void) { pthread_mutex_unlock(&registry_lock); }
#endif

static Instance *live_instances = NULL;

static void register_instance(Instance *inst)
{
    lock_registry();
    inst->next = live_instances;
    live_instances = inst;
    unlock_registry();
}

/* The live instance at address c, taken off the list when `unlink` is set; NULL if there
 * is none.  Compares addresses only: a freed or foreign c is never dereferenced. */
static Instance *find_instance(fmi2Component c, int unlink)
{
    Instance *found = NULL;
    lock_registry();
    for (Instance **link = &live_instances; *link != NULL; link = &(*link)->next) {
        if ((void *)*link == c) {
            found = *link;
            if (unlink) *link = found->next;
            break;
        }
    }
    unlock_registry();
    return found;
}

static Instance *as_instance(fmi2Component c)
{
    Instance *inst = c == NULL ? NULL : find_instance(c, 0);
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

static void reset_values(Instance *inst)
{
    for (size_t i = 0; i < n_st(); i++) inst->x[i] = model->x0[i];
    for (size_t k = 0; k < n_in(); k++) inst->u[k] = 0.0;
    inst->time = 0.0;
}

/* Release an instance that is not (or no longer) on the live list. */
static void free_instance(Instance *inst)
{
    fmi2CallbackFreeMemory release = inst->free_memory;
    void *blocks[] = {inst->instance_name, inst->x, inst->u, inst->y, inst->dx,
                      inst->Phi, inst->Gamma, inst->work};
    memset(inst, 0, sizeof *inst); /* no magic, no pointers left behind */
    for (size_t i = 0; i < sizeof blocks / sizeof blocks[0]; i++) {
        if (blocks[i] != NULL) release(blocks[i]);
    }
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
    if ((fmuType == fmi2ModelExchange && !FLEXSAT_MODEL_EXCHANGE)
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

    const size_t n = at_least_one(n_st()), m = at_least_one(n_in()), p = at_least_one(n_out());
    inst->instance_name = (char *)allocate(strlen(instanceName) + 1, 1);
    inst->x = (double *)allocate(n, sizeof(double));
    inst->u = (double *)allocate(m, sizeof(double));
    inst->y = (double *)allocate(p, sizeof(double));
    inst->dx = (double *)allocate(n, sizeof(double));
    int ok = inst->instance_name && inst->x && inst->u && inst->y && inst->dx;
    if (ok && fmuType == fmi2CoSimulation) {
        inst->Phi = (double *)allocate(n * n, sizeof(double));
        inst->Gamma = (double *)allocate(n * m, sizeof(double));
        inst->work = (double *)allocate(lm_workspace_size(model), sizeof(double));
        ok = inst->Phi && inst->Gamma && inst->work;
    }
    if (!ok) {
        LOG_ERROR(&report, "fmi2Instantiate: out of memory.");
        free_instance(inst);
        return NULL;
    }
    strcpy(inst->instance_name, instanceName);
    reset_values(inst);
    register_instance(inst);
    return inst;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    /* taken off the live list first: a second call with the same handle finds nothing */
    Instance *inst = c == NULL ? NULL : find_instance(c, 1);
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
    inst->time = startTime;
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
    reset_values(inst);
    inst->cached_step = 0.0;
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
              "these states and inputs).", function, what, name, inst->time);
    return inst->type == fmi2ModelExchange ? fmi2Discard : fmi2Error;
}

/* ---------------------------------------------------------------- variable access */

typedef enum { KIND_INPUT, KIND_OUTPUT, KIND_STATE, KIND_DERIVATIVE, KIND_INVALID } Kind;

static Kind kind_of(fmi2ValueReference vr, size_t *index)
{
    const size_t m = n_in(), p = n_out(), n = n_st();
    size_t r = vr;
    if (r < m) { *index = r; return KIND_INPUT; }
    r -= m;
    if (r < p) { *index = r; return KIND_OUTPUT; }
    r -= p;
    if (r < n) { *index = r; return KIND_STATE; }
    r -= n;
    if (r < n) { *index = r; return KIND_DERIVATIVE; }
    return KIND_INVALID;
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
    lm_outputs(model, inst->x, inst->u, inst->y);
    lm_derivatives(model, inst->x, inst->u, inst->dx);
    for (size_t i = 0; i < nvr; i++) {
        size_t k;
        switch (kind_of(vr[i], &k)) {
        case KIND_INPUT: value[i] = inst->u[k]; break;
        case KIND_OUTPUT: value[i] = inst->y[k]; break;
        case KIND_STATE: value[i] = inst->x[k]; break;
        case KIND_DERIVATIVE: value[i] = inst->dx[k]; break;
        default:
            LOG_ERROR(inst, "fmi2GetReal: unknown value reference %u.", (unsigned)vr[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        size_t k;
        const Kind kind = kind_of(vr[i], &k);
        if ((kind == KIND_OUTPUT || kind == KIND_DERIVATIVE) && !isfinite(value[i]))
            return overflowed(inst, "fmi2GetReal",
                              kind == KIND_OUTPUT ? "output" : "derivative of state",
                              kind == KIND_OUTPUT ? model->output_names[k]
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
        const Kind kind = kind_of(vr[i], &k);
        if (kind == KIND_INVALID) {
            LOG_ERROR(inst, "fmi2SetReal: unknown value reference %u.", (unsigned)vr[i]);
            return fmi2Error;
        }
        if (kind == KIND_OUTPUT || kind == KIND_DERIVATIVE) {
            LOG_ERROR(inst, "fmi2SetReal: %s is calculated and cannot be set.",
                      kind == KIND_OUTPUT ? model->output_names[k] : "a state derivative");
            return fmi2Error;
        }
        if (kind == KIND_STATE && !before_init) {
            LOG_ERROR(inst, "fmi2SetReal: state %s can only be set before initialisation "
                      "is finished (use fmi2SetContinuousStates in Model Exchange).",
                      model->state_names[k]);
            return fmi2Error;
        }
        if (!isfinite(value[i])) {
            LOG_ERROR(inst, "fmi2SetReal: %s %s must be finite; got %g. The value was not set.",
                      kind == KIND_INPUT ? "input" : "state",
                      kind == KIND_INPUT ? model->input_names[k] : model->state_names[k],
                      value[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        size_t k = 0;
        if (kind_of(vr[i], &k) == KIND_INPUT) inst->u[k] = value[i];
        else inst->x[k] = value[i];
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

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    (void)FMUstate;
    return unsupported(c, "fmi2GetFMUstate", "canGetAndSetFMUstate");
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    (void)FMUstate;
    return unsupported(c, "fmi2SetFMUstate", "canGetAndSetFMUstate");
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    (void)FMUstate;
    return unsupported(c, "fmi2FreeFMUstate", "canGetAndSetFMUstate");
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate,
                                                  size_t *size)
{
    (void)FMUstate;
    (void)size;
    return unsupported(c, "fmi2SerializedFMUstateSize", "canSerializeFMUstate");
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                             fmi2Byte serializedState[], size_t size)
{
    (void)FMUstate;
    (void)serializedState;
    (void)size;
    return unsupported(c, "fmi2SerializeFMUstate", "canSerializeFMUstate");
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c,
                                               const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate *FMUstate)
{
    (void)serializedState;
    (void)size;
    (void)FMUstate;
    return unsupported(c, "fmi2DeSerializeFMUstate", "canSerializeFMUstate");
}

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
                                                    const fmi2ValueReference vUnknown_ref[],
                                                    size_t nUnknown,
                                                    const fmi2ValueReference vKnown_ref[],
                                                    size_t nKnown, const fmi2Real dvKnown[],
                                                    fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative");
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
    inst->time = time;
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
    for (size_t i = 0; i < nx; i++) inst->x[i] = x[i];
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
    lm_derivatives(model, inst->x, inst->u, inst->dx);
    for (size_t i = 0; i < nx; i++) derivatives[i] = inst->dx[i];
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
    for (size_t i = 0; i < nx; i++) x[i] = inst->x[i];
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
    for (size_t i = 0; i < nx; i++) x_nominal[i] = 1.0;
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

/* Phi, Gamma for the step h: the precomputed default step when h equals it up to the
 * round-off of the master's time arithmetic, else the last step computed here, else a
 * fresh exponential (exact to round-off for any h). */
static int transition_matrices(Instance *inst, double t, double h, const double **Phi,
                               const double **Gamma)
{
    const double tolerance = 16.0 * 2.220446049250313e-16 * (fabs(t) + h);
    if (fabs(h - model->default_step) <= tolerance) {
        *Phi = model->Phi0;
        *Gamma = model->Gamma0;
        return 0;
    }
    if (inst->cached_step > 0.0 && fabs(h - inst->cached_step) <= tolerance) {
        *Phi = inst->Phi;
        *Gamma = inst->Gamma;
        return 0;
    }
    inst->cached_step = 0.0;
    const int status = lm_discretize(model, h, inst->Phi, inst->Gamma, inst->work);
    if (status != 0) return status;
    inst->cached_step = h;
    *Phi = inst->Phi;
    *Gamma = inst->Gamma;
    return 0;
}

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *inst = checked_cs(c, "fmi2DoStep", STATE_STEP_COMPLETE);
    if (inst == NULL) return fmi2Error;
    const double t = currentCommunicationPoint, h = communicationStepSize;
    if (!(h > 0.0) || !isfinite(h)) {
        LOG_ERROR(inst, "fmi2DoStep: communicationStepSize must be positive and finite [s]; "
                  "got %g.", h);
        return fmi2Error;
    }
    if (!isfinite(t) || fabs(t - inst->time) > 1e-9 * (1.0 + fabs(inst->time))) {
        LOG_ERROR(inst, "fmi2DoStep: currentCommunicationPoint must equal the time reached "
                  "so far, %.17g s; got %.17g s.", inst->time, t);
        return fmi2Error;
    }
    if (n_st() > 0) {
        const double *Phi, *Gamma;
        const int status = transition_matrices(inst, t, h, &Phi, &Gamma);
        if (status != 0) {
            LOG_ERROR(inst, "fmi2DoStep: the transition matrix for the step %g s is not "
                      "finite (code %d); the state was not changed.", h, status);
            inst->state = STATE_STEP_FAILED;
            return fmi2Discard;
        }
        lm_step(model, Phi, Gamma, inst->x, inst->u, inst->dx);
        for (size_t i = 0; i < n_st(); i++) {
            if (!isfinite(inst->dx[i])) {
                LOG_ERROR(inst, "fmi2DoStep: state %s overflowed at t = %g s; the state was "
                          "not changed.", model->state_names[i], t + h);
                inst->state = STATE_STEP_FAILED;
                return fmi2Discard;
            }
        }
        /* the outputs at the new state must be finite too, with the inputs held */
        lm_outputs(model, inst->dx, inst->u, inst->y);
        for (size_t i = 0; i < n_out(); i++) {
            if (!isfinite(inst->y[i])) {
                LOG_ERROR(inst, "fmi2DoStep: output %s overflowed at t = %g s; the state was "
                          "not changed.", model->output_names[i], t + h);
                inst->state = STATE_STEP_FAILED;
                return fmi2Discard;
            }
        }
        for (size_t i = 0; i < n_st(); i++) inst->x[i] = inst->dx[i];
    }
    inst->time = t + h;
    return fmi2OK;
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
    *value = inst->time;
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
