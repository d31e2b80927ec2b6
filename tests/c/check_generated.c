/*
 * Calls the generated C of the example models without Python (compiled and run by
 * tests/backends/test_c_backend.py together with generated planar_2r.c and ur10e.c).
 *
 * Independent checks:
 *   - planar_2r against the seed's closed forms: x = l1 c1 + l2 c12, y = l1 s1 + l2 s12,
 *     J = [[-l1 s1 - l2 s12, -l2 s12], [l1 c1 + l2 c12, l2 c12]] (seed eq. 8.56);
 *   - ur10e: rotations orthonormal, frames' last link = fk, the geometric Jacobian equal
 *     to central finite differences of fk (linear rows: dp/dq; angular rows: vee(dR/dq R^T));
 *   - batch entry points equal single calls bit for bit, with shared (stride 0) and
 *     per-configuration parameters; the combined function equals the separate ones;
 *   - the float32 variants agree with double to single precision;
 *   - the generated branch-free sin/cos agrees with libm (large, special and odd arguments).
 * Prints one line per failed check and "N passed, N failed"; exits 1 on any failure.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "planar_2r.h"
#include "ur10e.h"

static int passed = 0;
static int failed = 0;

static void check(int ok, const char *what, int index)
{
    if (ok) {
        ++passed;
    } else {
        ++failed;
        printf("FAILED: %s (case %d)\n", what, index);
    }
}

static double max_abs_diff(const double *a, const double *b, size_t n)
{
    double worst = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double d = fabs(a[i] - b[i]);
        if (!(d <= worst)) {
            worst = d; /* also catches NaN */
        }
    }
    return worst;
}

/* A deterministic pseudo-random angle in [-pi, pi) (linear congruential generator). */
static double random_angle(unsigned long *state)
{
    *state = (*state * 6364136223846793005UL + 1442695040888963407UL) & 0xffffffffffffUL;
    return ((double)*state / 281474976710656.0 - 0.5) * 2.0 * 3.141592653589793;
}

static void check_planar_2r(void)
{
    const double lengths[3][2] = {{PLANAR_2R_DEFAULT_l1, PLANAR_2R_DEFAULT_l2}, {0.3, 0.2}, {1.5, 0.25}};
    unsigned long state = 1;
    for (int k = 0; k < 30; ++k) {
        const double q[2] = {random_angle(&state), random_angle(&state)};
        const double l1 = lengths[k % 3][0], l2 = lengths[k % 3][1];
        const double c1 = cos(q[0]), s1 = sin(q[0]), c12 = cos(q[0] + q[1]), s12 = sin(q[0] + q[1]);
        double T[16], J[4];
        planar_2r_fk(q, l1, l2, T);
        planar_2r_jacobian(q, l1, l2, J);
        const double T_want[16] = {c12, -s12, 0, l1 * c1 + l2 * c12, s12, c12, 0, l1 * s1 + l2 * s12,
                                   0, 0, 1, 0, 0, 0, 0, 1};
        const double J_want[4] = {-l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12};
        check(max_abs_diff(T, T_want, 16) < 1e-15, "planar_2r fk = closed form", k);
        check(max_abs_diff(J, J_want, 4) < 1e-15, "planar_2r jacobian = seed eq. 8.56", k);
    }
}

/* The generated sin/cos (Cody-Waite reduction and polynomials, libm beyond its range) against
 * libm: cos(t1) and sin(t1) are the position of a one-link arm (l1 = 1, l2 = 0). */
static void check_sincos_against_libm(void)
{
    unsigned long state = 5;
    double worst = 0.0;
    int k = 0;
    for (; k < 20000; ++k) {
        double x;
        if (k < 8) {
            const double special[8] = {0.0, -0.0, 1.5707963267948966, 3.141592653589793, -4.71238898038469,
                                       1e-300, 99999.9, 3.0e6};
            x = special[k];
        } else {
            const double scale = k % 4 == 0 ? 1e5 : k % 4 == 1 ? 1e3 : k % 4 == 2 ? 10.0 : 1e6;
            x = random_angle(&state) / 3.141592653589793 * scale;
        }
        const double q[2] = {x, 0.0};
        double T[16];
        planar_2r_fk(q, 1.0, 0.0, T);
        worst = fmax(worst, fmax(fabs(T[3] - cos(x)), fabs(T[7] - sin(x))));
        worst = fmax(worst, fmax(fabs(T[0] - cos(x)), fabs(T[4] - sin(x))));
    }
    check(worst < 4e-16, "generated sincos = libm within 2 ulp on |x| <= 1e6", k);
    const double odd[3] = {NAN, INFINITY, -INFINITY};
    for (int i = 0; i < 3; ++i) {
        const double q[2] = {odd[i], 0.0};
        double T[16];
        planar_2r_fk(q, 1.0, 0.0, T);
        check(isnan(T[3]) && isnan(T[7]), "generated sincos of NaN and inf is NaN", i);
    }
}

#define N_BATCH 64

static void check_planar_2r_batch(void)
{
    double q[N_BATCH * 2], params[N_BATCH * 2], T[N_BATCH * 16], J[N_BATCH * 4];
    unsigned long state = 2;
    for (int i = 0; i < N_BATCH; ++i) {
        q[2 * i] = random_angle(&state);
        q[2 * i + 1] = random_angle(&state);
        params[2 * i] = 0.1 + 0.01 * i;
        params[2 * i + 1] = 0.2 - 0.001 * i;
    }
    planar_2r_fk_batch(N_BATCH, q, params, 2, T);
    planar_2r_jacobian_batch(N_BATCH, q, params, 0, J);
    for (int i = 0; i < N_BATCH; ++i) {
        double T1[16], J1[4];
        planar_2r_fk(q + 2 * i, params[2 * i], params[2 * i + 1], T1);
        planar_2r_jacobian(q + 2 * i, params[0], params[1], J1);
        check(memcmp(T1, T + 16 * i, sizeof T1) == 0, "planar_2r fk_batch (per-configuration parameters)", i);
        check(memcmp(J1, J + 4 * i, sizeof J1) == 0, "planar_2r jacobian_batch (shared parameters)", i);
    }
}

#define UR_PARAMS UR10E_DEFAULT_d1, UR10E_DEFAULT_a2, UR10E_DEFAULT_a3, UR10E_DEFAULT_d4, UR10E_DEFAULT_d5, UR10E_DEFAULT_d6

static void ur10e_pose(const double *q, double *T)
{
    ur10e_fk(q, UR_PARAMS, T);
}

static void check_ur10e(void)
{
    unsigned long state = 3;
    const double h = 1e-6;
    for (int k = 0; k < 20; ++k) {
        double q[6], T[16], frames[6][16], Jg[36];
        for (int j = 0; j < 6; ++j) {
            q[j] = random_angle(&state);
        }
        ur10e_pose(q, T);
        ur10e_frames(q, UR_PARAMS, frames[0], frames[1], frames[2], frames[3], frames[4], frames[5]);
        ur10e_jacobian_geometric(q, UR10E_DEFAULT_a2, UR10E_DEFAULT_a3, UR10E_DEFAULT_d4, UR10E_DEFAULT_d5,
                                 UR10E_DEFAULT_d6, Jg);
        check(max_abs_diff(frames[5], T, 16) < 1e-15, "ur10e frames: base_T_wrist3 = fk", k);
        double worst = 0.0;
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                double dot = 0.0;
                for (int m = 0; m < 3; ++m) {
                    dot += T[4 * r + m] * T[4 * c + m];
                }
                worst = fmax(worst, fabs(dot - (r == c ? 1.0 : 0.0)));
            }
        }
        check(worst < 1e-14, "ur10e fk rotation orthonormal", k);
        for (int j = 0; j < 6; ++j) {
            double qp[6], qm[6], Tp[16], Tm[16];
            memcpy(qp, q, sizeof qp);
            memcpy(qm, q, sizeof qm);
            qp[j] += h;
            qm[j] -= h;
            ur10e_pose(qp, Tp);
            ur10e_pose(qm, Tm);
            double err = 0.0;
            for (int r = 0; r < 3; ++r) {
                err = fmax(err, fabs((Tp[4 * r + 3] - Tm[4 * r + 3]) / (2 * h) - Jg[6 * r + j]));
            }
            /* skew(w) = dR/dq R^T: w = (S[2][1], S[0][2], S[1][0]). */
            double S[3][3];
            for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 3; ++c) {
                    S[r][c] = 0.0;
                    for (int m = 0; m < 3; ++m) {
                        S[r][c] += (Tp[4 * r + m] - Tm[4 * r + m]) / (2 * h) * T[4 * c + m];
                    }
                }
            }
            const double w[3] = {S[2][1], S[0][2], S[1][0]};
            for (int r = 0; r < 3; ++r) {
                err = fmax(err, fabs(w[r] - Jg[6 * (3 + r) + j]));
            }
            check(err < 1e-8, "ur10e jacobian_geometric = finite differences of fk", 6 * k + j);
        }
    }
}

static void check_combined_batch_and_float32(void)
{
    enum { N = 16 };
    /* combined parameters: d1 a2 a3 d4 d5 d6 m1..m6 g; each part takes the ones it uses (see ur10e.h):
     * M: a2 a3 d4 d5 d6 m1..m6; V: a2 a3 d4 d5 d6 m2..m6; G: a2 a3 d5 d6 m2..m6 g. */
    double params[13] = {UR_PARAMS, UR10E_DEFAULT_m1, UR10E_DEFAULT_m2, UR10E_DEFAULT_m3, UR10E_DEFAULT_m4,
                         UR10E_DEFAULT_m5, UR10E_DEFAULT_m6, UR10E_DEFAULT_g};
    const double coriolis_params[10] = {params[1], params[2], params[3], params[4], params[5], params[7],
                                        params[8], params[9], params[10], params[11]};
    const double gravity_params[10] = {params[1], params[2], params[4], params[5], params[7],
                                       params[8], params[9], params[10], params[11], params[12]};
    double q[N * 6], qd[N * 6];
    double T[N * 16], J[N * 36], M[N * 36], V[N * 6], G[N * 6];
    double s_fk[N * 16], s_J[N * 36], s_M[N * 36], s_V[N * 6], s_G[N * 6];
    double q2[N * 2], T2[N * 16], J2[N * 4], params2[2] = {0.3, 0.2};
    float qf[N * 2], paramsf[2] = {0.3f, 0.2f}, Tf[N * 16], Jf[N * 4];
    unsigned long state = 4;
    for (int i = 0; i < N * 6; ++i) {
        q[i] = random_angle(&state);
        qd[i] = random_angle(&state);
    }
    for (int i = 0; i < N * 2; ++i) {
        q2[i] = random_angle(&state);
        qf[i] = (float)q2[i];
    }
    ur10e_fk_batch(N, q, params, 0, T);
    ur10e_jacobian_batch(N, q, params + 1, 0, J);
    ur10e_mass_matrix_batch(N, q, params + 1, 0, M);
    ur10e_coriolis_vector_batch(N, q, qd, coriolis_params, 0, V);
    ur10e_gravity_vector_batch(N, q, gravity_params, 0, G);
    ur10e_combined_batch(N, q, qd, params, 0, s_fk, s_J, s_M, s_V, s_G);
    planar_2r_fk_batch(N, q2, params2, 0, T2);
    planar_2r_jacobian_batch(N, q2, params2, 0, J2);
    planar_2r_fk_batch_f32(N, qf, paramsf, 0, Tf);
    planar_2r_jacobian_batch_f32(N, qf, paramsf, 0, Jf);
    for (int i = 0; i < N; ++i) {
        double T1[16];
        ur10e_fk(q + 6 * i, UR_PARAMS, T1);
        check(memcmp(T1, T + 16 * i, sizeof T1) == 0, "ur10e fk_batch = fk", i);
        check(max_abs_diff(s_fk + 16 * i, T1, 16) < 1e-14, "ur10e combined base_T_tcp = fk", i);
        check(max_abs_diff(s_J + 36 * i, J + 36 * i, 36) < 1e-13, "ur10e combined J = jacobian", i);
        check(max_abs_diff(s_M + 36 * i, M + 36 * i, 36) < 1e-12, "ur10e combined M = mass_matrix", i);
        check(max_abs_diff(s_V + 6 * i, V + 6 * i, 6) < 1e-12, "ur10e combined V = coriolis_vector", i);
        check(max_abs_diff(s_G + 6 * i, G + 6 * i, 6) < 1e-12, "ur10e combined G = gravity_vector", i);
        double err = 0.0;
        for (int m = 0; m < 16; ++m) {
            err = fmax(err, fabs((double)Tf[16 * i + m] - T2[16 * i + m]));
        }
        for (int m = 0; m < 4; ++m) {
            err = fmax(err, fabs((double)Jf[4 * i + m] - J2[4 * i + m]));
        }
        check(err < 1e-6, "planar_2r float32 = double to single precision", i);
    }
}

int main(void)
{
    check_planar_2r();
    check_planar_2r_batch();
    check_sincos_against_libm();
    check_ur10e();
    check_combined_batch_and_float32();
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
