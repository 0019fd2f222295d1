/* C host test of the DoublePendulum FMU: includes the generated header (and
 * through it the standard fmi2Functions.h, so a signature drift fails to
 * compile), links the binary of the unpacked archive (the one FMU binary,
 * told by resources/ that it is this plant), runs a 10 s free swing and
 * checks the energy, then checks that a bad call returns fmi2Error with a
 * log message. Arguments: the GUID and the fmuResourceLocation URI. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "eigenmpc.h"

static int errors_logged = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    if (status == fmi2Error) errors_logged++;
    printf("  [%s] %s: %s\n", category, name, text);
}

#define CHECK(cond)                                                   \
    do {                                                              \
        if (!(cond)) {                                                \
            fprintf(stderr, "FAILED at line %d: %s\n", __LINE__, #cond); \
            return 1;                                                 \
        }                                                             \
    } while (0)

int main(int argc, char **argv) {
    CHECK(argc == 3); /* the GUID from modelDescription.xml, the resources' URI */
    fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};
    fmi2Component c = fmi2Instantiate("plant", fmi2CoSimulation, argv[1], argv[2], &callbacks,
                                      fmi2False, fmi2False);
    CHECK(c != NULL);
    const fmi2ValueReference start[] = {DOUBLE_PENDULUM_VR_Q0_1, DOUBLE_PENDULUM_VR_Q0_2};
    const fmi2Real q0[] = {1.0, -0.5};
    CHECK(fmi2SetReal(c, start, 2, q0) == fmi2OK);
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK);
    const fmi2ValueReference energy = DOUBLE_PENDULUM_VR_ENERGY;
    fmi2Real e0, e;
    CHECK(fmi2GetReal(c, &energy, 1, &e0) == fmi2OK);
    /* V = g (m1 + m2) l1 (1 - cos q1) + g m2 l2 (1 - cos(q1 + q2)) at rest */
    CHECK(fabs(e0 - (9.81 * 2.0 * (1.0 - cos(1.0)) + 9.81 * (1.0 - cos(0.5)))) < 1e-12);
    double t = 0.0, worst = 0.0;
    for (int k = 0; k < 1000; k++) {
        CHECK(fmi2DoStep(c, t, 0.01, fmi2True) == fmi2OK);
        t += 0.01;
        CHECK(fmi2GetReal(c, &energy, 1, &e) == fmi2OK);
        if (fabs(e - e0) / e0 > worst) worst = fabs(e - e0) / e0;
    }
    printf("10 s free swing: max relative energy drift %.2e\n", worst);
    CHECK(worst < 1e-8);
    const fmi2Real nan_torque = NAN;
    const fmi2ValueReference tau = DOUBLE_PENDULUM_VR_TAU1;
    CHECK(fmi2SetReal(c, &tau, 1, &nan_torque) == fmi2Error);
    CHECK(errors_logged == 1);
    CHECK(fmi2DoStep(c, t, 0.01, fmi2True) == fmi2Error); /* error state */
    CHECK(fmi2Reset(c) == fmi2OK);
    CHECK(strcmp(fmi2GetVersion(), "2.0") == 0);
    fmi2FreeInstance(c);
    printf("1 passed, 0 failed\n");
    return 0;
}
