/* publisher.c — smoke test of an installed libln (tests/installed/run): publishes COUNT
 * robot/joint_state samples on smoke.state at 200 Hz; position[j] is cycle * (j + 1) / 1000.
 * Built against the installed headers and library with pkg-config, or by SConstruct. */
#define _POSIX_C_SOURCE 200809L /* nanosleep */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <ln/ln.h>

#include "messages.h"

int main(int argc, char** argv)
{
    int count = argc > 1 ? atoi(argv[1]) : 400;
    int rc = LN_VERSION_CHECK();
    ln_client* clnt;
    ln_outport* pub;
    if (rc == LN_OK)
        rc = ln_client_create(&clnt, "smoke_publisher", NULL);
    if (rc == LN_OK)
        rc = ln_publish(clnt, &pub, "smoke.state", ROBOT_JOINT_STATE_MD, NULL);
    if (rc != LN_OK) {
        fprintf(stderr, "publisher: %s (%s)\n", ln_strerror(rc), ln_last_error());
        return 1;
    }
    printf("publisher: libln %s, %d samples\n", ln_version(), count);
    fflush(stdout);
    robot_joint_state_t js = {0};
    struct timespec period = {0, 5000000};
    for (int cycle = 1; cycle <= count; cycle++) {
        js.cycle = (uint32_t)cycle;
        for (int j = 0; j < 7; j++)
            js.position[j] = cycle * (j + 1) / 1000.0;
        if ((rc = ln_write(pub, &js, sizeof js, 0.1)) < 0) {
            fprintf(stderr, "publisher: write: %s\n", ln_strerror(rc));
            return 1;
        }
        nanosleep(&period, NULL);
    }
    ln_unpublish(pub);
    ln_client_destroy(clnt);
    return 0;
}
