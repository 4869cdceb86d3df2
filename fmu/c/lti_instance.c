/* flexsat FMU template: values, stepping, FMU states and partial derivatives of one
 * instance, shared by the FMI 2.0 and FMI 3.0 API layers (see lti_instance.h).
 *
 * Serialised FMU state (native byte order and double format; li_deserialize refuses bytes
 * written by another model, another layout version or a machine of another byte order):
 *
 *     offset  size       content
 *          0     8       "FLXSSTAT"
 *          8     4       layout version (uint32, 1)
 *         12     4       1 for a discrete-time model, else 0 (uint32)
 *         16    24       n_states, n_inputs, n_outputs (uint64 each)
 *         40    48       the model's GUID / instantiation token, NUL-padded
 *         88    24       time, start_time, next_sample (double each)
 *        112     4       mode of the API layer's state machine (uint32)
 *        116     4       kind of instance, 0 Model Exchange, 1 Co-Simulation (uint32)
 *        120  8(n+m+p)   x, u, y_hold (double each)
 *
 * The mode is part of the FMU state, as in the Reference-FMUs: an importer may restore a
 * state saved after initialisation into a freshly instantiated instance (fmusim's
 * --initial-fmu-state-file does) and go on stepping.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
#else
#include <pthread.h>
#endif

#include "lti_instance.h"

static const LinearModel *const model = &linear_model;

#define SNAPSHOT_MAGIC 0x464c5354u /* "FLST" */
#define SERIAL_HEADER 120
#define SERIAL_VERSION 1u
#define GUID_BYTES 48
/* Co-simulation steps up to this many samples are taken one by one (exactly as the
 * monolithic sampled loop computes them); longer ones by binary powering. */
#define ITERATED_SAMPLES 1000.0

struct LiSnapshot {
    LiSnapshot *next;
    unsigned magic;
    double time;
    double start_time;
    double next_sample;
    unsigned mode;  /* the API layer's state machine state */
    unsigned kind;  /* 0 Model Exchange, 1 Co-Simulation */
    double *values; /* x[n], u[m], y_hold[p] */
};

static size_t at_least_one(size_t k) { return k > 0 ? k : 1; }

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

static LiNode *live_instances = NULL;

void li_register(LiNode *node)
{
    lock_registry();
    node->next = live_instances;
    live_instances = node;
    unlock_registry();
}

LiNode *li_find(const void *address, int unlink)
{
    LiNode *found = NULL;
    if (address == NULL) return NULL;
    lock_registry();
    for (LiNode **link = &live_instances; *link != NULL; link = &(*link)->next) {
        if ((const void *)*link == address) {
            found = *link;
            if (unlink) *link = found->next;
            break;
        }
    }
    unlock_registry();
    return found;
}

/* ---------------------------------------------------------------- values */

int li_discrete(void) { return model->sample_period > 0.0; }

size_t li_n_derivatives(void) { return li_discrete() ? 0 : model->n_states; }

unsigned long li_time_vr(void)
{
    return (unsigned long)(model->n_inputs + model->n_outputs + model->n_states
                           + li_n_derivatives());
}

unsigned long li_clock_vr(void) { return li_time_vr() + 1; }

int li_allocate(LiValues *v, LiAllocate allocate, LiRelease release, int cosimulation)
{
    const size_t n = at_least_one(model->n_states), m = at_least_one(model->n_inputs);
    const size_t p = at_least_one(model->n_outputs);
    memset(v, 0, sizeof *v);
    v->allocate = allocate;
    v->release = release;
    v->x = (double *)allocate(n, sizeof(double));
    v->u = (double *)allocate(m, sizeof(double));
    v->y = (double *)allocate(p, sizeof(double));
    v->dx = (double *)allocate(n, sizeof(double));
    v->y_hold = (double *)allocate(p, sizeof(double));
    v->x_next = (double *)allocate(n, sizeof(double));
    v->y_next = (double *)allocate(p, sizeof(double));
    int ok = v->x && v->u && v->y && v->dx && v->y_hold && v->x_next && v->y_next;
    if (ok && cosimulation) {
        v->Phi = (double *)allocate(n * n, sizeof(double));
        v->Gamma = (double *)allocate(n * m, sizeof(double));
        v->work = (double *)allocate(lm_workspace_size(model), sizeof(double));
        ok = v->Phi && v->Gamma && v->work;
    }
    if (!ok) {
        li_free(v);
        return -1;
    }
    li_reset(v);
    return 0;
}

void li_free(LiValues *v)
{
    LiRelease release = v->release;
    if (release == NULL) return;
    for (LiSnapshot *s = v->snapshots; s != NULL;) {
        LiSnapshot *next = s->next;
        s->magic = 0;
        release(s);
        s = next;
    }
    double *blocks[] = {v->x, v->u, v->y, v->dx, v->y_hold, v->x_next, v->y_next, v->Phi,
                        v->Gamma, v->work};
    memset(v, 0, sizeof *v); /* no pointers left behind */
    for (size_t i = 0; i < sizeof blocks / sizeof blocks[0]; i++) {
        if (blocks[i] != NULL) release(blocks[i]);
    }
}

void li_reset(LiValues *v)
{
    for (size_t i = 0; i < model->n_states; i++) v->x[i] = model->x0[i];
    for (size_t k = 0; k < model->n_inputs; k++) v->u[k] = 0.0;
    v->cached_step = 0.0;
    li_start(v, 0.0);
    /* held outputs before any sample: those of the initial state */
    lm_outputs(model, v->x, v->u, v->y_hold);
}

void li_start(LiValues *v, double start_time)
{
    v->time = start_time;
    v->start_time = start_time;
    v->next_sample = 0.0;
}

static double tolerance(void) { return LI_SAMPLE_TOLERANCE * model->sample_period; }

double li_next_sample_time(const LiValues *v)
{
    return v->start_time + v->next_sample * model->sample_period;
}

int li_sample_pending(const LiValues *v)
{
    return li_discrete() && li_next_sample_time(v) <= v->time + tolerance();
}

void li_update_outputs(LiValues *v)
{
    if (li_discrete() && !li_sample_pending(v)) {
        for (size_t i = 0; i < model->n_outputs; i++) v->y[i] = v->y_hold[i];
        return;
    }
    lm_outputs(model, v->x, v->u, v->y);
}

void li_update_derivatives(LiValues *v)
{
    lm_derivatives(model, v->x, v->u, v->dx);
}

static int first_not_finite(size_t count, const double *values, size_t *index)
{
    for (size_t i = 0; i < count; i++) {
        if (!isfinite(values[i])) {
            *index = i;
            return 1;
        }
    }
    return 0;
}

/* ---------------------------------------------------------------- continuous time */

/* Phi, Gamma for the step h: the precomputed default step when h equals it up to the
 * round-off of the master's time arithmetic, else the last step computed here, else a
 * fresh exponential (exact to round-off for any h). */
static int transition_matrices(LiValues *v, double t, double h, const double **Phi,
                               const double **Gamma)
{
    const double tol = 16.0 * 2.220446049250313e-16 * (fabs(t) + h);
    if (fabs(h - model->default_step) <= tol) {
        *Phi = model->Phi0;
        *Gamma = model->Gamma0;
        return 0;
    }
    if (v->cached_step > 0.0 && fabs(h - v->cached_step) <= tol) {
        *Phi = v->Phi;
        *Gamma = v->Gamma;
        return 0;
    }
    v->cached_step = 0.0;
    const int status = lm_discretize(model, h, v->Phi, v->Gamma, v->work);
    if (status != 0) return status;
    v->cached_step = h;
    *Phi = v->Phi;
    *Gamma = v->Gamma;
    return 0;
}

static int continuous_step(LiValues *v, double t, double h, size_t *index, int *detail)
{
    if (model->n_states > 0) {
        const double *Phi, *Gamma;
        const int status = transition_matrices(v, t, h, &Phi, &Gamma);
        if (status != 0) {
            *detail = status;
            return LI_NO_TRANSITION;
        }
        lm_step(model, Phi, Gamma, v->x, v->u, v->x_next);
        if (first_not_finite(model->n_states, v->x_next, index)) return LI_STATE_OVERFLOW;
        /* the outputs at the new state must be finite too, with the inputs held */
        lm_outputs(model, v->x_next, v->u, v->y);
        if (first_not_finite(model->n_outputs, v->y, index)) return LI_OUTPUT_OVERFLOW;
        memcpy(v->x, v->x_next, model->n_states * sizeof(double));
    }
    v->time = t + h;
    return LI_OK;
}

/* ---------------------------------------------------------------- discrete time */

/* Number of samples still to take at instants before t_end (less the tolerance). */
static double samples_before(const LiValues *v, double t_end)
{
    const double T = model->sample_period, limit = t_end - tolerance();
    if (!(li_next_sample_time(v) < limit)) return 0.0;
    double last = ceil((limit - v->start_time) / T) - 1.0;
    if (!(last < LI_MAX_SAMPLES_PER_STEP + v->next_sample)) return LI_MAX_SAMPLES_PER_STEP;
    while (v->start_time + (last + 1.0) * T < limit) last += 1.0;
    while (last >= v->next_sample && !(v->start_time + last * T < limit)) last -= 1.0;
    return last - v->next_sample + 1.0;
}

/* Take `count` samples with the inputs held, then set the time to t_after.  Works on
 * scratch vectors and commits only if every state and output is finite. */
static int take_samples(LiValues *v, double count, double t_after, size_t *index)
{
    const size_t n = model->n_states, p = model->n_outputs;
    double *z = v->dx, *z_next = v->x_next, *y = v->y_next;
    memcpy(z, v->x, n * sizeof(double));
    if (count <= ITERATED_SAMPLES) {
        for (double j = 0.0; j < count; j += 1.0) {
            lm_outputs(model, z, v->u, y);      /* y_k = C x_k + D u */
            lm_derivatives(model, z, v->u, z_next); /* x_k+1 = A x_k + B u */
            memcpy(z, z_next, n * sizeof(double));
        }
    } else {
        /* x_{count-1} by powering, then the last sample as above */
        if (lm_sample_power(model, count - 1.0, v->x, v->u, z_next, v->work) != 0) {
            *index = 0;
            return LI_STATE_OVERFLOW;
        }
        memcpy(z, z_next, n * sizeof(double));
        lm_outputs(model, z, v->u, y);
        lm_derivatives(model, z, v->u, z_next);
        memcpy(z, z_next, n * sizeof(double));
    }
    if (first_not_finite(n, z, index)) return LI_STATE_OVERFLOW;
    if (first_not_finite(p, y, index)) return LI_OUTPUT_OVERFLOW;
    /* a sample pending at t_after shows C x + D u at once: that must be finite as well */
    const double T = model->sample_period;
    if (v->start_time + (v->next_sample + count) * T <= t_after + tolerance()) {
        lm_outputs(model, z, v->u, v->y);
        if (first_not_finite(p, v->y, index)) return LI_OUTPUT_OVERFLOW;
    }
    memcpy(v->x, z, n * sizeof(double));
    memcpy(v->y_hold, y, p * sizeof(double));
    v->next_sample += count;
    v->time = t_after;
    return LI_OK;
}

int li_do_step(LiValues *v, double t, double h, size_t *index, int *detail)
{
    *index = 0;
    *detail = 0;
    if (!li_discrete()) return continuous_step(v, t, h, index, detail);
    const double count = samples_before(v, t + h);
    if (count >= LI_MAX_SAMPLES_PER_STEP) return LI_TOO_MANY_SAMPLES;
    if (count == 0.0) {
        v->time = t + h;
        return LI_OK;
    }
    return take_samples(v, count, t + h, index);
}

int li_sample_now(LiValues *v, size_t *index)
{
    *index = 0;
    if (!li_sample_pending(v)) return LI_NOT_A_SAMPLE;
    return take_samples(v, 1.0, v->time, index);
}

/* ---------------------------------------------------------------- variables */

LiKind li_kind(unsigned long vr, size_t *index)
{
    const size_t m = model->n_inputs, p = model->n_outputs, n = model->n_states;
    unsigned long r = vr;
    *index = 0;
    if (r < m) { *index = r; return LI_INPUT; }
    r -= m;
    if (r < p) { *index = r; return LI_OUTPUT; }
    r -= p;
    if (r < n) { *index = r; return LI_STATE; }
    r -= n;
    if (r < li_n_derivatives()) { *index = r; return LI_DERIVATIVE; }
    if (vr == li_time_vr()) return LI_TIME;
    if (li_discrete() && vr == li_clock_vr()) return LI_CLOCK;
    return LI_INVALID;
}

int li_is_unknown(LiKind kind)
{
    return kind == LI_OUTPUT || (kind == LI_DERIVATIVE && !li_discrete());
}

int li_is_known(LiKind kind)
{
    return kind == LI_INPUT || (kind == LI_STATE && !li_discrete());
}

double li_partial(const LiValues *v, LiKind unknown, size_t i, LiKind known, size_t k)
{
    const size_t n = model->n_states, m = model->n_inputs;
    if (li_discrete()) return li_sample_pending(v) ? model->D[i * m + k] : 0.0;
    if (unknown == LI_OUTPUT)
        return known == LI_STATE ? model->C[i * n + k] : model->D[i * m + k];
    return known == LI_STATE ? model->A[i * n + k] : model->B[i * m + k];
}

/* ---------------------------------------------------------------- FMU states */

static size_t n_values(void) { return model->n_states + model->n_inputs + model->n_outputs; }

LiSnapshot *li_find_snapshot(const LiValues *v, const void *address)
{
    if (address == NULL) return NULL;
    for (LiSnapshot *s = v->snapshots; s != NULL; s = s->next) {
        if ((const void *)s == address) return s->magic == SNAPSHOT_MAGIC ? s : NULL;
    }
    return NULL;
}

static LiSnapshot *new_snapshot(LiValues *v)
{
    /* header and values in one block; sizeof(LiSnapshot) is a multiple of the alignment
     * of double (the struct holds doubles) */
    LiSnapshot *s = (LiSnapshot *)v->allocate(1, sizeof(LiSnapshot) + n_values() * sizeof(double));
    if (s == NULL) return NULL;
    memset(s, 0, sizeof *s);
    s->magic = SNAPSHOT_MAGIC;
    s->values = (double *)(s + 1);
    s->next = v->snapshots;
    v->snapshots = s;
    return s;
}

static void copy_values_into(const LiValues *v, LiSnapshot *s)
{
    const size_t n = model->n_states, m = model->n_inputs, p = model->n_outputs;
    s->time = v->time;
    s->start_time = v->start_time;
    s->next_sample = v->next_sample;
    memcpy(s->values, v->x, n * sizeof(double));
    memcpy(s->values + n, v->u, m * sizeof(double));
    memcpy(s->values + n + m, v->y_hold, p * sizeof(double));
}

int li_save(LiValues *v, LiSnapshot **state, unsigned mode, unsigned kind)
{
    LiSnapshot *s = *state;
    if (s != NULL) {
        if (li_find_snapshot(v, s) == NULL) return -2;
    } else {
        s = new_snapshot(v);
        if (s == NULL) return -1;
    }
    copy_values_into(v, s);
    s->mode = mode;
    s->kind = kind;
    *state = s;
    return 0;
}

unsigned li_snapshot_mode(const LiSnapshot *state) { return state->mode; }

void li_restore(LiValues *v, const LiSnapshot *s)
{
    const size_t n = model->n_states, m = model->n_inputs, p = model->n_outputs;
    v->time = s->time;
    v->start_time = s->start_time;
    v->next_sample = s->next_sample;
    memcpy(v->x, s->values, n * sizeof(double));
    memcpy(v->u, s->values + n, m * sizeof(double));
    memcpy(v->y_hold, s->values + n + m, p * sizeof(double));
}

int li_discard(LiValues *v, LiSnapshot *state)
{
    for (LiSnapshot **link = &v->snapshots; *link != NULL; link = &(*link)->next) {
        if (*link == state) {
            *link = state->next;
            memset(state, 0, sizeof *state);
            v->release(state);
            return 0;
        }
    }
    return -2;
}

size_t li_serialized_size(void) { return SERIAL_HEADER + n_values() * sizeof(double); }

static void put_u32(unsigned char *at, uint32_t value) { memcpy(at, &value, sizeof value); }
static void put_u64(unsigned char *at, uint64_t value) { memcpy(at, &value, sizeof value); }
static uint32_t get_u32(const unsigned char *at)
{
    uint32_t value;
    memcpy(&value, at, sizeof value);
    return value;
}
static uint64_t get_u64(const unsigned char *at)
{
    uint64_t value;
    memcpy(&value, at, sizeof value);
    return value;
}

void li_serialize(const LiSnapshot *s, unsigned char *buffer)
{
    memset(buffer, 0, SERIAL_HEADER);
    memcpy(buffer, "FLXSSTAT", 8);
    put_u32(buffer + 8, SERIAL_VERSION);
    put_u32(buffer + 12, li_discrete() ? 1u : 0u);
    put_u64(buffer + 16, (uint64_t)model->n_states);
    put_u64(buffer + 24, (uint64_t)model->n_inputs);
    put_u64(buffer + 32, (uint64_t)model->n_outputs);
    const size_t guid_length = strlen(model->guid);
    memcpy(buffer + 40, model->guid, guid_length < GUID_BYTES ? guid_length : GUID_BYTES);
    const double times[3] = {s->time, s->start_time, s->next_sample};
    memcpy(buffer + 88, times, sizeof times);
    put_u32(buffer + 112, (uint32_t)s->mode);
    put_u32(buffer + 116, (uint32_t)s->kind);
    memcpy(buffer + SERIAL_HEADER, s->values, n_values() * sizeof(double));
}

int li_deserialize(LiValues *v, const unsigned char *data, size_t size, unsigned kind,
                   unsigned valid_modes, LiSnapshot **state, const char **why)
{
    char guid[GUID_BYTES];
    const size_t guid_length = strlen(model->guid);
    memset(guid, 0, sizeof guid);
    memcpy(guid, model->guid, guid_length < GUID_BYTES ? guid_length : GUID_BYTES);
    *why = NULL;
    if (size != li_serialized_size()) *why = "its size is not that of a state of this model";
    else if (memcmp(data, "FLXSSTAT", 8) != 0) *why = "it does not start like a flexsat FMU state";
    else if (get_u32(data + 8) != SERIAL_VERSION)
        *why = "it has another layout version or byte order";
    else if (get_u32(data + 12) != (li_discrete() ? 1u : 0u)
             || get_u64(data + 16) != (uint64_t)model->n_states
             || get_u64(data + 24) != (uint64_t)model->n_inputs
             || get_u64(data + 32) != (uint64_t)model->n_outputs
             || memcmp(data + 40, guid, GUID_BYTES) != 0)
        *why = "it was saved by another model (GUID or sizes differ)";
    else if (get_u32(data + 116) != (uint32_t)kind)
        *why = kind == 1 ? "it was saved by a Model Exchange instance; this one is Co-Simulation"
                         : "it was saved by a Co-Simulation instance; this one is Model Exchange";
    else {
        const uint32_t mode = get_u32(data + 112);
        if (mode == 0 || (mode & (mode - 1)) != 0 || (mode & valid_modes) != mode)
            *why = "its mode is not one this instance can be in";
    }
    if (*why != NULL) return -3;
    double times[3];
    memcpy(times, data + 88, sizeof times);
    if (!isfinite(times[0]) || !isfinite(times[1]) || !(times[2] >= 0.0)
        || !(times[2] < LI_MAX_SAMPLES_PER_STEP) || times[2] != floor(times[2])) {
        *why = "its time or sample index is not a finite, valid number";
        return -3;
    }
    for (size_t i = 0; i < n_values(); i++) {
        double value;
        memcpy(&value, data + SERIAL_HEADER + i * sizeof(double), sizeof value);
        if (!isfinite(value)) {
            *why = "it holds a value that is not finite";
            return -3;
        }
    }
    LiSnapshot *s = *state;
    if (s != NULL) {
        if (li_find_snapshot(v, s) == NULL) {
            *why = "the FMUstate given to overwrite is not a state of this instance";
            return -2;
        }
    } else {
        s = new_snapshot(v);
        if (s == NULL) return -1;
    }
    s->time = times[0];
    s->start_time = times[1];
    s->next_sample = times[2];
    s->mode = get_u32(data + 112);
    s->kind = kind;
    memcpy(s->values, data + SERIAL_HEADER, n_values() * sizeof(double));
    *state = s;
    return 0;
}
