/* C host test of the plain C API of the EigenMPC controller: includes the
 * generated header and the standard fmi2Functions.h (the FMI functions of the
 * same library are declared there, so a signature drift fails to compile),
 * links libeigenmpc_fmu, and closes the loop around a double pendulum written
 * here in C (RK4, 10 substeps per 25 ms sample): from q = (0.05, 0.05) the
 * curved controller must pump the energy to within 5 % of E_ref = 14 J with
 * torques inside +-tau_max, then follow E_ref = 8 J set at run time. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "eigenmpc.h"

#define CHECK(cond)                                                          \
    do {                                                                     \
        if (!(cond)) {                                                       \
            fprintf(stderr, "FAILED at line %d: %s\n", __LINE__, #cond);     \
            return 1;                                                        \
        }                                                                    \
    } while (0)

/* The paper's double pendulum (m = l = 1, g = 9.81): q1 from the downward
 * vertical, q2 relative to link 1. */
static const double G = 9.81;

static void derivative(const double z[4], const double tau[2], double dz[4]) {
    double q1 = z[0], q2 = z[1], w1 = z[2], w2 = z[3];
    double c2 = cos(q2), s2 = sin(q2);
    double m11 = 3.0 + 2.0 * c2, m12 = 1.0 + c2, m22 = 1.0;
    /* Coriolis/centrifugal and gravity terms: M qdd = tau - h - g */
    double h1 = -s2 * (2.0 * w1 * w2 + w2 * w2);
    double h2 = s2 * w1 * w1;
    double g1 = G * (2.0 * sin(q1) + sin(q1 + q2));
    double g2 = G * sin(q1 + q2);
    double r1 = tau[0] - h1 - g1, r2 = tau[1] - h2 - g2;
    double det = m11 * m22 - m12 * m12;
    dz[0] = w1;
    dz[1] = w2;
    dz[2] = (m22 * r1 - m12 * r2) / det;
    dz[3] = (m11 * r2 - m12 * r1) / det;
}

static void rk4(double z[4], const double tau[2], double h) {
    double k1[4], k2[4], k3[4], k4[4], y[4];
    derivative(z, tau, k1);
    for (int i = 0; i < 4; i++) y[i] = z[i] + 0.5 * h * k1[i];
    derivative(y, tau, k2);
    for (int i = 0; i < 4; i++) y[i] = z[i] + 0.5 * h * k2[i];
    derivative(y, tau, k3);
    for (int i = 0; i < 4; i++) y[i] = z[i] + h * k3[i];
    derivative(y, tau, k4);
    for (int i = 0; i < 4; i++) z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

static double energy(const double z[4]) {
    double q1 = z[0], q2 = z[1], w1 = z[2], w2 = z[3], c2 = cos(q2);
    double v = G * 2.0 * (1.0 - cos(q1)) + G * (1.0 - cos(q1 + q2));
    return v + 0.5 * ((3.0 + 2.0 * c2) * w1 * w1 + 2.0 * (1.0 + c2) * w1 * w2 + w2 * w2);
}

/* Runs `samples` controller samples; returns 0 or the failing line. */
static int run(EigenMpc *mpc, double z[4], int samples, double tau_max, double *worst_tau) {
    double tau[2];
    for (int k = 0; k < samples; k++) {
        int status = eigenmpc_step(mpc, z, tau);
        if (status != EIGENMPC_STATUS_SOLVED) {
            fprintf(stderr, "sample %d: status %d (%s)\n", k, status, eigenmpc_last_error(mpc));
            return __LINE__;
        }
        for (int j = 0; j < 2; j++) {
            if (!(fabs(tau[j]) <= tau_max)) return __LINE__;
            if (fabs(tau[j]) > *worst_tau) *worst_tau = fabs(tau[j]);
        }
        for (int i = 0; i < 10; i++) rk4(z, tau, 0.0025);
    }
    return 0;
}

int main(void) {
    CHECK(strcmp(fmi2GetVersion(), "2.0") == 0);
    CHECK(EIGENMPC_CHART_COEFFICIENTS == 10);

    /* Bad arguments: NULL / refused config give NULL and a message. */
    char err[256] = "";
    CHECK(eigenmpc_create(NULL, NULL, err, sizeof err) == NULL);
    CHECK(strstr(err, "NULL") != NULL);
    EigenMpcConfig cfg = eigenmpc_config_default(EIGENMPC_VARIANT_CURVED);
    cfg.tau_max = -1.0;
    CHECK(eigenmpc_create(&cfg, NULL, err, sizeof err) == NULL);
    CHECK(strstr(err, "tau_max") != NULL);
    printf("refused config: %s\n", err);

    cfg = eigenmpc_config_default(EIGENMPC_VARIANT_CURVED);
    CHECK(cfg.e_ref == 14.0 && cfg.horizon == 80 && cfg.sample_period == 0.025);
    EigenMpc *mpc = eigenmpc_create(&cfg, NULL, err, sizeof err);
    CHECK(mpc != NULL);
    double tau[2] = {NAN, NAN};
    CHECK(eigenmpc_step(mpc, NULL, tau) == EIGENMPC_STATUS_BAD_ARGUMENT);
    CHECK(eigenmpc_step(NULL, tau, tau) == EIGENMPC_STATUS_BAD_ARGUMENT);
    CHECK(isnan(tau[0]));
    CHECK(eigenmpc_set_e_ref(mpc, -3.0) == EIGENMPC_STATUS_BAD_ARGUMENT);
    CHECK(strstr(eigenmpc_last_error(mpc), "e_ref") != NULL);

    /* 25 s at E_ref = 14 J from a small initial displacement. */
    double z[4] = {0.05, 0.05, 0.0, 0.0};
    double worst_tau = 0.0;
    double e0 = energy(z);
    int line = run(mpc, z, 1000, cfg.tau_max, &worst_tau);
    CHECK(line == 0);
    double e14 = energy(z);
    EigenMpcStepInfo info;
    CHECK(eigenmpc_last_step(mpc, &info) == 0);
    printf("E: %.4f J -> %.4f J after 25 s (E_ref 14 J), max |tau| %.4f N m, last solve %.3f ms, %u QP iterations\n",
           e0, e14, worst_tau, info.solve_time * 1e3, info.qp_iterations);
    CHECK(fabs(e14 - 14.0) < 0.05 * 14.0);
    CHECK(worst_tau > 0.9); /* the torque bound was active while pumping */
    CHECK(fabs(info.energy - energy(z)) < 0.05); /* energy of the last step's state */

    /* E_ref changed at run time to 8 J: 30 s later the energy is there. */
    CHECK(eigenmpc_set_e_ref(mpc, 8.0) == 0);
    worst_tau = 0.0;
    line = run(mpc, z, 1200, cfg.tau_max, &worst_tau);
    CHECK(line == 0);
    double e8 = energy(z);
    printf("E: %.4f J 30 s after E_ref -> 8 J\n", e8);
    /* The default reference is computed: the chart follows E_ref (with the
     * fixed 14 J chart the energy settled 4.6 % above, at 8.37 J). */
    CHECK(fabs(e8 - 8.0) < 0.01 * 8.0);

    eigenmpc_free(mpc);
    eigenmpc_free(NULL);

    /* Any robot by the FMU's parameter names: a 3-link chain with a lighter
     * last link and Coulomb friction at joint 2, straight variant. */
    const char *names[] = {"m[3]", "cf[2]", "variant", "E_ref", "tau_max"};
    const double values[] = {0.5, 0.05, EIGENMPC_VARIANT_STRAIGHT, 6.0, 2.0};
    mpc = eigenmpc_create_named(3, names, values, 5, err, sizeof err);
    CHECK(mpc != NULL);
    CHECK(eigenmpc_joints(mpc) == 3);
    double z3[6] = {0.05, 0.05, 0.05, 0.0, 0.0, 0.0}, tau3[3] = {NAN, NAN, NAN};
    CHECK(eigenmpc_step(mpc, z3, tau3) == EIGENMPC_STATUS_SOLVED);
    for (int j = 0; j < 3; j++) CHECK(isfinite(tau3[j]) && fabs(tau3[j]) <= 2.0);
    eigenmpc_free(mpc);
    /* Online adaptation by name: the base parameters are readable. */
    const char *adapt_names[] = {"adapt", "adapt_period"};
    const double adapt_values[] = {1.0, 0.5};
    mpc = eigenmpc_create_named(2, adapt_names, adapt_values, 2, err, sizeof err);
    CHECK(mpc != NULL);
    double z2[4] = {0.05, 0.05, 0.0, 0.0}, tau2[2], theta[11];
    CHECK(eigenmpc_step(mpc, z2, tau2) >= 0);
    CHECK(eigenmpc_estimate(mpc, NULL, 0) == 11);
    CHECK(eigenmpc_estimate(mpc, theta, 11) == 11);
    /* the paper's pendulum: A[1,1] = 2, G[2] = 9.81 (kg m^2, N m) */
    CHECK(fabs(theta[0] - 2.0) < 1e-12 && fabs(theta[4] - 9.81) < 1e-12);
    eigenmpc_free(mpc);
    const char *bad[] = {"mu[1]"};
    CHECK(eigenmpc_create_named(2, bad, values, 1, err, sizeof err) == NULL);
    CHECK(strstr(err, "mu[1] is not a variable") != NULL);
    printf("refused name: %s\n", err);
    printf("1 passed, 0 failed\n");
    return 0;
}
