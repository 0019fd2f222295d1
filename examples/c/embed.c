#include <stdio.h>

#include "eigenmpc.h"

int main(void) {
    EigenMpcConfig cfg = eigenmpc_config_default(EIGENMPC_VARIANT_CURVED); /* the paper's */
    char err[256];
    EigenMpc *mpc = eigenmpc_create(&cfg, NULL /* chart computed from cfg's model */, err,
                                    sizeof err);
    if (!mpc) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    double z[4] = {0.05, 0.05, 0.0, 0.0}; /* measured q1, q2, qd1, qd2 */
    double tau[2];
    int status = eigenmpc_step(mpc, z, tau); /* every cfg.sample_period s; 0 = solved */
    printf("status %d, tau = %.4f / %.4f N m\n", status, tau[0], tau[1]);
    eigenmpc_free(mpc);
    return status;
}
