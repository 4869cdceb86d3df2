/* flexsat FMU template: the values of one instance and everything both FMI versions do
 * with them (no FMI types here).
 *
 * fmi2Functions.c and fmi3Functions.c are thin API layers over this file, as the
 * Reference-FMUs keep fmi2Functions.c / fmi3Functions.c over model.c and cosimulation.c:
 * the stepping (exact zero-order hold for continuous-time models, sampling for
 * discrete-time ones), the FMU states and their serialised form, the partial derivatives
 * and the list of live instances are written once.
 *
 * Value references (fixed layout, the same in modelDescription.xml of both versions):
 *     inputs       0 .. m-1
 *     outputs      m .. m+p-1
 *     states       m+p .. m+p+n-1
 *     derivatives  m+p+n .. m+p+2n-1        (continuous-time models only)
 *     time         next after the above      (FMI 3.0: the independent variable)
 *     clock        time + 1                  (FMI 3.0, discrete-time models: the sample clock)
 *
 * Discrete-time models (sample period T > 0) sample at t_k = t_start + k T.  A sample
 * computes the output y_k = C x_k + D u(t_k), which is then held until the next sample,
 * and the next state x_{k+1} = A x_k + B u(t_k).  At a sample instant whose sample is
 * still to be taken ("pending") the outputs are C x_k + D u with the inputs as set now, so
 * a master that sets the inputs at t_k and reads the outputs sees the direct feedthrough.
 * A co-simulation step from t to t + h takes every pending sample in [t, t + h) with the
 * inputs held, so the FMU updates at its sample period whatever the master's step: a
 * step longer than T takes several samples, a shorter one holds the outputs between
 * samples.  Instants within LI_SAMPLE_TOLERANCE * T of a communication point count as at it.
 */
#ifndef FLEXSAT_LTI_INSTANCE_H
#define FLEXSAT_LTI_INSTANCE_H

#include <stddef.h>

#include "linear_model.h"

#if defined(LM_PREFIX)
#define li_register LM_PREFIXED(LM_PREFIX, li_register)
#define li_find LM_PREFIXED(LM_PREFIX, li_find)
#define li_allocate LM_PREFIXED(LM_PREFIX, li_allocate)
#define li_free LM_PREFIXED(LM_PREFIX, li_free)
#define li_reset LM_PREFIXED(LM_PREFIX, li_reset)
#define li_start LM_PREFIXED(LM_PREFIX, li_start)
#define li_discrete LM_PREFIXED(LM_PREFIX, li_discrete)
#define li_sample_pending LM_PREFIXED(LM_PREFIX, li_sample_pending)
#define li_next_sample_time LM_PREFIXED(LM_PREFIX, li_next_sample_time)
#define li_update_outputs LM_PREFIXED(LM_PREFIX, li_update_outputs)
#define li_update_derivatives LM_PREFIXED(LM_PREFIX, li_update_derivatives)
#define li_do_step LM_PREFIXED(LM_PREFIX, li_do_step)
#define li_sample_now LM_PREFIXED(LM_PREFIX, li_sample_now)
#define li_kind LM_PREFIXED(LM_PREFIX, li_kind)
#define li_n_derivatives LM_PREFIXED(LM_PREFIX, li_n_derivatives)
#define li_time_vr LM_PREFIXED(LM_PREFIX, li_time_vr)
#define li_clock_vr LM_PREFIXED(LM_PREFIX, li_clock_vr)
#define li_partial LM_PREFIXED(LM_PREFIX, li_partial)
#define li_is_unknown LM_PREFIXED(LM_PREFIX, li_is_unknown)
#define li_is_known LM_PREFIXED(LM_PREFIX, li_is_known)
#define li_find_snapshot LM_PREFIXED(LM_PREFIX, li_find_snapshot)
#define li_save LM_PREFIXED(LM_PREFIX, li_save)
#define li_restore LM_PREFIXED(LM_PREFIX, li_restore)
#define li_snapshot_mode LM_PREFIXED(LM_PREFIX, li_snapshot_mode)
#define li_discard LM_PREFIXED(LM_PREFIX, li_discard)
#define li_serialized_size LM_PREFIXED(LM_PREFIX, li_serialized_size)
#define li_serialize LM_PREFIXED(LM_PREFIX, li_serialize)
#define li_deserialize LM_PREFIXED(LM_PREFIX, li_deserialize)
#endif

/* Sample instants this close to a communication point, relative to T, count as at it. */
#define LI_SAMPLE_TOLERANCE 1e-6
/* A step that spans this many samples or more is refused (2^53: sample indices are whole
 * doubles). */
#define LI_MAX_SAMPLES_PER_STEP 9007199254740992.0

typedef void *(*LiAllocate)(size_t count, size_t size);
typedef void (*LiRelease)(void *block);

/* ---------------------------------------------------------------- live instances */

/* The first member of each API layer's instance: the list of live instances, guarded by a
 * mutex, lets every call look its handle up by address without dereferencing it. */
typedef struct LiNode {
    struct LiNode *next;
} LiNode;

void li_register(LiNode *node);

/* The live node at `address` (taken off the list when `unlink`), or NULL.  Compares
 * addresses only: a freed or foreign pointer is never dereferenced. */
LiNode *li_find(const void *address, int unlink);

/* ---------------------------------------------------------------- values */

typedef struct LiSnapshot LiSnapshot;

typedef struct {
    LiAllocate allocate;
    LiRelease release;
    double time;         /* [s] */
    double start_time;   /* origin of the sample grid [s] */
    double next_sample;  /* index k of the next sample to take, at start_time + k T */
    double *x;           /* states, size max(n, 1) */
    double *u;           /* inputs, size max(m, 1) */
    double *y;           /* outputs as last computed, size max(p, 1) */
    double *dx;          /* derivatives / scratch, size max(n, 1) */
    double *y_hold;      /* outputs held since the last sample (discrete time) */
    double *x_next;      /* scratch, size max(n, 1) */
    double *y_next;      /* scratch, size max(p, 1) */
    double *Phi;         /* co-simulation: transition matrices for cached_step */
    double *Gamma;
    double cached_step;  /* step of Phi, Gamma; 0 if none */
    double *work;        /* workspace of lm_discretize / lm_sample_power */
    LiSnapshot *snapshots; /* FMU states of this instance */
} LiValues;

/* Allocate the arrays (co-simulation: also the transition matrices and workspace) and set
 * the start values.  Returns 0, or -1 when out of memory (everything allocated is freed). */
int li_allocate(LiValues *v, LiAllocate allocate, LiRelease release, int cosimulation);

/* Free the arrays and every FMU state of the instance. */
void li_free(LiValues *v);

/* Start values: x = x0, u = 0, time 0, sample grid from 0. */
void li_reset(LiValues *v);

/* Begin at start_time: the time and the origin of the sample grid. */
void li_start(LiValues *v, double start_time);

int li_discrete(void);
int li_sample_pending(const LiValues *v);
double li_next_sample_time(const LiValues *v);

/* v->y: C x + D u, or for a discrete-time model between samples the held outputs. */
void li_update_outputs(LiValues *v);

/* v->dx = A x + B u (continuous time). */
void li_update_derivatives(LiValues *v);

enum {
    LI_OK = 0,
    LI_NO_TRANSITION = 1,    /* the transition matrix of the step is not finite; detail */
    LI_STATE_OVERFLOW = 2,   /* state `index` would not be finite */
    LI_OUTPUT_OVERFLOW = 3,  /* output `index` would not be finite */
    LI_TOO_MANY_SAMPLES = 4, /* the step spans LI_MAX_SAMPLES_PER_STEP samples or more */
    LI_NOT_A_SAMPLE = 5      /* li_sample_now away from a sample instant */
};

/* One co-simulation step from t to t + h (h > 0 and finite, checked by the caller).  On
 * any failure nothing changes.  `index` names the state or output that overflowed,
 * `detail` the code of lm_discretize. */
int li_do_step(LiValues *v, double t, double h, size_t *index, int *detail);

/* Take the pending sample now (FMI 3.0 Event Mode with the sample clock active). */
int li_sample_now(LiValues *v, size_t *index);

/* ---------------------------------------------------------------- variables */

typedef enum { LI_INPUT, LI_OUTPUT, LI_STATE, LI_DERIVATIVE, LI_TIME, LI_CLOCK, LI_INVALID } LiKind;

LiKind li_kind(unsigned long vr, size_t *index);
size_t li_n_derivatives(void);
unsigned long li_time_vr(void);
unsigned long li_clock_vr(void);

/* The unknowns of the partial derivatives: outputs and (continuous time) state
 * derivatives; the knowns: inputs and (continuous time) states. */
int li_is_unknown(LiKind kind);
int li_is_known(LiKind kind);

/* Partial derivative d unknown / d known (both checked with the two functions above) of
 * the linear maps:
 *     output i:      d/d state k = C[i][k],  d/d input k = D[i][k]
 *     derivative i:  d/d state k = A[i][k],  d/d input k = B[i][k]
 * For a discrete-time model, outputs by inputs: D at a pending sample, 0 between samples
 * (the outputs are held). */
double li_partial(const LiValues *v, LiKind unknown, size_t i, LiKind known, size_t k);

/* ---------------------------------------------------------------- FMU states */

/* The FMU state of this instance at `address`, or NULL (never dereferences a pointer that
 * is not one of its states). */
LiSnapshot *li_find_snapshot(const LiValues *v, const void *address);

/* Save the values, with the API layer's mode (its state machine state) and the kind of
 * instance (0 Model Exchange, 1 Co-Simulation), into *state: a new state if *state is
 * NULL, else the given one, which must be a state of this instance.  Returns 0, -1 out of
 * memory, -2 not our state. */
int li_save(LiValues *v, LiSnapshot **state, unsigned mode, unsigned kind);

/* Restore the values; the API layer restores its mode from li_snapshot_mode. */
void li_restore(LiValues *v, const LiSnapshot *state);
unsigned li_snapshot_mode(const LiSnapshot *state);

/* Free a state of this instance.  Returns 0, or -2 if it is not one. */
int li_discard(LiValues *v, LiSnapshot *state);

/* Serialised form, native byte order (the layout is in lti_instance.c). */
size_t li_serialized_size(void);
void li_serialize(const LiSnapshot *state, unsigned char *buffer);

/* Read a serialised state into a new state of this instance (or into *state, if it is one
 * of its states), of this kind of instance, whose mode must be one bit of valid_modes.
 * Returns 0, -1 out of memory, -2 *state is not ours, -3 if the bytes are not a state of
 * this model and kind (*why says why). */
int li_deserialize(LiValues *v, const unsigned char *data, size_t size, unsigned kind,
                   unsigned valid_modes, LiSnapshot **state, const char **why);

#endif
