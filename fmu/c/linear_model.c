/* flexsat FMU template: arithmetic of the linear model (no FMI calls here).
 *
 * The zero-order-hold discretisation uses the block-matrix identity (Van Loan 1978)
 *
 *     expm([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, I]],
 *     Phi = expm(A h),  Gamma = int_0^h expm(A s) ds B,
 *
 * which is exact for any A (singular or not), and evaluates the exponential by scaling and
 * squaring with the degree-13 Pade approximant of Higham (2005), accurate to double
 * round-off for any norm after scaling.
 *
 * References
 *   C. F. Van Loan, "Computing integrals involving the matrix exponential",
 *     IEEE Trans. Automatic Control 23(3), 395-404, 1978.
 *   N. J. Higham, "The scaling and squaring method for the matrix exponential revisited",
 *     SIAM J. Matrix Anal. Appl. 26(4), 1179-1193, 2005 (Algorithm 2.3, Table 2.3).
 */
#include <math.h>
#include <string.h>

#include "linear_model.h"

void lm_derivatives(const LinearModel *model, const double *x, const double *u, double *dx)
{
    const size_t n = model->n_states, m = model->n_inputs;
    for (size_t i = 0; i < n; i++) {
        double sum = 0.0;
        const double *a = model->A + i * n;
        const double *b = model->B + i * m;
        for (size_t j = 0; j < n; j++) sum += a[j] * x[j];
        for (size_t k = 0; k < m; k++) sum += b[k] * u[k];
        dx[i] = sum;
    }
}

void lm_outputs(const LinearModel *model, const double *x, const double *u, double *y)
{
    const size_t n = model->n_states, m = model->n_inputs, p = model->n_outputs;
    for (size_t i = 0; i < p; i++) {
        double sum = 0.0;
        const double *c = model->C + i * n;
        const double *d = model->D + i * m;
        for (size_t j = 0; j < n; j++) sum += c[j] * x[j];
        for (size_t k = 0; k < m; k++) sum += d[k] * u[k];
        y[i] = sum;
    }
}

void lm_step(const LinearModel *model, const double *Phi, const double *Gamma,
             const double *x, const double *u, double *x_next)
{
    const size_t n = model->n_states, m = model->n_inputs;
    for (size_t i = 0; i < n; i++) {
        double sum = 0.0;
        const double *f = Phi + i * n;
        const double *g = Gamma + i * m;
        for (size_t j = 0; j < n; j++) sum += f[j] * x[j];
        for (size_t k = 0; k < m; k++) sum += g[k] * u[k];
        x_next[i] = sum;
    }
}

/* Workspace: 9 matrices of size N x N, N pivot indices and N balancing factors,
 * N = n_states + n_inputs. */
size_t lm_workspace_size(const LinearModel *model)
{
    const size_t N = model->n_states + model->n_inputs;
    return 9 * N * N + 2 * N + 1;
}

/* R = P Q for N x N row-major matrices (R must not alias P or Q). */
static void matmul(size_t N, const double *P, const double *Q, double *R)
{
    memset(R, 0, N * N * sizeof(double));
    for (size_t i = 0; i < N; i++) {
        double *r = R + i * N;
        for (size_t k = 0; k < N; k++) {
            const double p = P[i * N + k];
            if (p == 0.0) continue;
            const double *q = Q + k * N;
            for (size_t j = 0; j < N; j++) r[j] += p * q[j];
        }
    }
}

static int all_finite(size_t count, const double *P)
{
    for (size_t i = 0; i < count; i++) if (!isfinite(P[i])) return 0;
    return 1;
}

static double norm_1(size_t N, const double *P)
{
    double norm = 0.0;
    for (size_t j = 0; j < N; j++) {
        double column = 0.0;
        for (size_t i = 0; i < N; i++) column += fabs(P[i * N + j]);
        if (column > norm) norm = column;
    }
    return norm;
}

/* Solve Q X = P in place (X overwrites P) by LU with partial pivoting; Q is destroyed. */
static int lu_solve(size_t N, double *Q, double *P, double *pivot)
{
    for (size_t k = 0; k < N; k++) {
        size_t best = k;
        double best_abs = fabs(Q[k * N + k]);
        for (size_t i = k + 1; i < N; i++) {
            const double v = fabs(Q[i * N + k]);
            if (v > best_abs) { best_abs = v; best = i; }
        }
        if (!(best_abs > 0.0)) return -2;
        pivot[k] = (double)best;
        if (best != k) {
            for (size_t j = 0; j < N; j++) {
                double t = Q[k * N + j]; Q[k * N + j] = Q[best * N + j]; Q[best * N + j] = t;
                t = P[k * N + j]; P[k * N + j] = P[best * N + j]; P[best * N + j] = t;
            }
        }
        const double diag = Q[k * N + k];
        for (size_t i = k + 1; i < N; i++) {
            const double l = Q[i * N + k] / diag;
            if (l == 0.0) continue;
            Q[i * N + k] = l;
            for (size_t j = k + 1; j < N; j++) Q[i * N + j] -= l * Q[k * N + j];
            for (size_t j = 0; j < N; j++) P[i * N + j] -= l * P[k * N + j];
        }
    }
    /* back substitution, all N right-hand sides at once */
    for (size_t kk = N; kk-- > 0;) {
        const double diag = Q[kk * N + kk];
        for (size_t j = 0; j < N; j++) {
            double sum = P[kk * N + j];
            for (size_t i = kk + 1; i < N; i++) sum -= Q[kk * N + i] * P[i * N + j];
            P[kk * N + j] = sum / diag;
        }
    }
    return 0;
}

int lm_discretize(const LinearModel *model, double h, double *Phi, double *Gamma, double *work)
{
    /* Pade [13/13] coefficients b_0..b_13 and theta_13 (Higham 2005, Table 2.3). */
    static const double b[14] = {
        64764752532480000.0, 32382376266240000.0, 7771770303897600.0,
        1187353796428800.0, 129060195264000.0, 10559470521600.0, 670442572800.0,
        33522128640.0, 1323241920.0, 40840800.0, 960960.0, 16380.0, 182.0, 1.0};
    const double theta13 = 5.371920351148152;

    const size_t n = model->n_states, m = model->n_inputs, N = n + m;
    if (!(h > 0.0) || !isfinite(h)) return -1;
    if (n == 0) return 0;

    double *M = work, *A2 = M + N * N, *A4 = A2 + N * N, *A6 = A4 + N * N;
    double *U = A6 + N * N, *V = U + N * N, *T = V + N * N, *P = T + N * N, *Q = P + N * N;
    double *pivot = Q + N * N;

    /* augmented matrix [[A h, B h], [0, 0]]; a step so long that A h or B h overflows has
     * no finite transition matrix to speak of (and an infinite entry would stall the
     * balancing below) */
    memset(M, 0, N * N * sizeof(double));
    for (size_t i = 0; i < n; i++) {
        for (size_t j = 0; j < n; j++) M[i * N + j] = model->A[i * n + j] * h;
        for (size_t k = 0; k < m; k++) M[i * N + n + k] = model->B[i * m + k] * h;
    }
    if (!all_finite(N * N, M)) return -3;

    /* Balance: M <- D^-1 M D with D diagonal powers of 2 (exact), so that rows and columns
     * have comparable norms (Parlett & Reinsch 1969, as LAPACK dgebal). A lightly damped
     * mode [[0, 1], [-w^2, -2 z w]] becomes nearly normal, which keeps the number of
     * squarings - and their error growth - small; expm(M) = D expm(D^-1 M D) D^-1.
     * Termination: the sweeps are capped; in a sweep, c and r are finite and positive (a
     * row whose sums overflow is left alone), so each while loop moves c by a factor 4
     * towards r and stops after at most ~1100 passes, or sooner at the cap on f (as
     * dgebal's sfmin/sfmax guards). */
    const double f_max = 1.3407807929942597e+154; /* 2^512: keeps every product finite */
    double *d = pivot + N; /* balancing scale factors */
    for (size_t i = 0; i < N; i++) d[i] = 1.0;
    for (int sweep = 0, changed = 1; changed && sweep < 100; sweep++) {
        changed = 0;
        for (size_t i = 0; i < N; i++) {
            double c = 0.0, r = 0.0;
            for (size_t j = 0; j < N; j++) {
                if (j == i) continue;
                c += fabs(M[j * N + i]);
                r += fabs(M[i * N + j]);
            }
            if (c == 0.0 || r == 0.0 || !isfinite(c + r)) continue;
            const double total = c + r;
            double f = 1.0;
            while (c < r / 2.0 && f < f_max) { f *= 2.0; c *= 4.0; }
            while (c > r * 2.0 && f > 1.0 / f_max) { f /= 2.0; c /= 4.0; }
            if ((c + r) / f < 0.95 * total) {
                changed = 1;
                d[i] *= f;
                for (size_t j = 0; j < N; j++) {
                    M[i * N + j] /= f;
                    M[j * N + i] *= f;
                }
            }
        }
    }

    /* ||M||_1 <= N max|m_ij|. When that bound passes 2^100, the powers up to M^8 used
     * below could overflow: scale M down first, by the 1-norm bound as in Higham (2005,
     * Algorithm 2.3), so that ||M 2^-s||_1 <= 4 < theta13. (Ordinary steps never get here.)
     * Binary exponents come from frexp, exactly: no log2 or pow, whose glibc 2.29 symbol
     * versions would keep the library from loading on older systems. */
    double largest = 0.0;
    for (size_t i = 0; i < N * N; i++) if (fabs(M[i]) > largest) largest = fabs(M[i]);
    int s = 0;
    if (largest > 0.0) {
        int e_largest, e_order;
        (void)frexp(largest, &e_largest);      /* largest < 2^e_largest */
        (void)frexp((double)N, &e_order);      /* N <= 2^e_order */
        if (e_largest + e_order > 101) {
            s = e_largest + e_order - 2;        /* N max|m| 2^-s < 2^2 <= theta13 */
            for (size_t i = 0; i < N * N; i++) M[i] = ldexp(M[i], -s);
        }
    }

    matmul(N, M, M, A2);
    matmul(N, A2, A2, A4);
    matmul(N, A4, A2, A6);

    /* Scaling s from alpha = max(||M^6||^(1/6), ||M^8||^(1/8)) rather than ||M||: the
     * exact powers are at hand, and for non-normal M they give far fewer squarings
     * (Al-Mohy & Higham 2009, eq. (3.10) and Algorithm 5.1 with eta_3).  The smallest
     * s1 >= 0 with alpha 2^-s1 <= theta13 is the smallest with ||M^6|| 2^(-6 s1) <=
     * theta13^6 and ||M^8|| 2^(-8 s1) <= theta13^8: found by exact ldexp comparisons, at
     * most 172 of them for any finite norm (2^1024 / 2^(6*171) < 1). */
    matmul(N, A4, A4, T);
    const double norm6 = norm_1(N, A6), norm8 = norm_1(N, T);
    if (!isfinite(norm6) || !isfinite(norm8)) return -3;
    const double theta6 = theta13 * theta13 * theta13 * theta13 * theta13 * theta13;
    const double theta8 = theta6 * theta13 * theta13;
    int s1 = 0;
    while (ldexp(norm6, -6 * s1) > theta6 || ldexp(norm8, -8 * s1) > theta8) s1++;
    if (s1 > 0) {
        for (size_t i = 0; i < N * N; i++) {
            M[i] = ldexp(M[i], -s1);
            A2[i] = ldexp(A2[i], -2 * s1);
            A4[i] = ldexp(A4[i], -4 * s1);
            A6[i] = ldexp(A6[i], -6 * s1);
        }
        s += s1;
    }

    /* U = M [A6 (b13 A6 + b11 A4 + b9 A2) + b7 A6 + b5 A4 + b3 A2 + b1 I] */
    for (size_t i = 0; i < N * N; i++) T[i] = b[13] * A6[i] + b[11] * A4[i] + b[9] * A2[i];
    matmul(N, A6, T, P);
    for (size_t i = 0; i < N * N; i++) P[i] += b[7] * A6[i] + b[5] * A4[i] + b[3] * A2[i];
    for (size_t i = 0; i < N; i++) P[i * N + i] += b[1];
    matmul(N, M, P, U);

    /* V = A6 (b12 A6 + b10 A4 + b8 A2) + b6 A6 + b4 A4 + b2 A2 + b0 I */
    for (size_t i = 0; i < N * N; i++) T[i] = b[12] * A6[i] + b[10] * A4[i] + b[8] * A2[i];
    matmul(N, A6, T, V);
    for (size_t i = 0; i < N * N; i++) V[i] += b[6] * A6[i] + b[4] * A4[i] + b[2] * A2[i];
    for (size_t i = 0; i < N; i++) V[i * N + i] += b[0];

    /* r_13(M) = (V - U)^-1 (V + U) */
    for (size_t i = 0; i < N * N; i++) {
        P[i] = V[i] + U[i];
        Q[i] = V[i] - U[i];
    }
    int status = lu_solve(N, Q, P, pivot);
    if (status != 0) return status;

    /* undo the scaling: expm(M 2^s) = expm(M)^(2^s).  s < 1100 for any finite M; the
     * squarings stop early once the result overflows (nothing finite can follow) or stops
     * changing (a stable system after many time constants: further squarings are exact
     * no-ops), so an absurdly long step costs little. */
    double *R = P, *S = T;
    for (int k = 0; k < s; k++) {
        matmul(N, R, R, S);
        if (!all_finite(N * N, S)) return -3;
        double *tmp = R; R = S; S = tmp;
        if (memcmp(R, S, N * N * sizeof(double)) == 0) break;
    }

    /* undo the balancing: expm(M) = D expm(B) D^-1 */
    for (size_t i = 0; i < n; i++) {
        for (size_t j = 0; j < n; j++) Phi[i * n + j] = R[i * N + j] * d[i] / d[j];
        for (size_t k = 0; k < m; k++) Gamma[i * m + k] = R[i * N + n + k] * d[i] / d[n + k];
    }
    for (size_t i = 0; i < n * n; i++) if (!isfinite(Phi[i])) return -3;
    for (size_t i = 0; i < n * m; i++) if (!isfinite(Gamma[i])) return -3;
    return 0;
}

int lm_sample_power(const LinearModel *model, double count, const double *x, const double *u,
                    double *z_out, double *work)
{
    const size_t n = model->n_states, m = model->n_inputs, N = n + m;
    if (n == 0) return 0;
    /* z_count = first n rows of [[A, B], [0, I]]^count [x; u] */
    double *R = work, *P = R + N * N, *S = P + N * N, *v = S + N * N;
    memset(R, 0, N * N * sizeof(double));
    memset(P, 0, N * N * sizeof(double));
    for (size_t i = 0; i < N; i++) R[i * N + i] = 1.0;
    for (size_t i = 0; i < n; i++) {
        for (size_t j = 0; j < n; j++) P[i * N + j] = model->A[i * n + j];
        for (size_t k = 0; k < m; k++) P[i * N + n + k] = model->B[i * m + k];
    }
    for (size_t k = 0; k < m; k++) P[(n + k) * N + n + k] = 1.0;
    /* binary powering: count = sum of bits; halving a whole double below 2^53 is exact */
    double e = count;
    while (e > 0.0) {
        const double half = floor(e / 2.0);
        if (e - 2.0 * half == 1.0) {
            matmul(N, R, P, S);
            memcpy(R, S, N * N * sizeof(double));
            if (!all_finite(N * N, R)) return -3;
        }
        e = half;
        if (e > 0.0) {
            matmul(N, P, P, S);
            memcpy(P, S, N * N * sizeof(double));
            if (!all_finite(N * N, P)) return -3;
        }
    }
    for (size_t j = 0; j < n; j++) v[j] = x[j];
    for (size_t k = 0; k < m; k++) v[n + k] = u[k];
    for (size_t i = 0; i < n; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < N; j++) sum += R[i * N + j] * v[j];
        z_out[i] = sum;
    }
    return all_finite(n, z_out) ? 0 : -3;
}
