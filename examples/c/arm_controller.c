/* arm_controller.c — a simulated 7-axis arm controller: every cycle it reads the newest
 * robot/command (latest mode), moves its joints toward the target with a first-order lag whose
 * gains the service arm.set_gains (robot/set_gains) sets, answers pending service calls
 * without blocking, and publishes robot/joint_state.  The manager comes from -ln_manager or
 * $LN_MANAGER.  Usage: arm_controller [CYCLES] [PERIOD_US] */
#define _POSIX_C_SOURCE 200809L /* clock_nanosleep */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ln/ln.h>

#include "robot_messages.h"

static int fail(const char* what, int rc)
{
    fprintf(stderr, "arm_controller: %s: %s (%s)\n", what, ln_last_error(), ln_error_name(rc));
    return 1;
}

/* arm.set_gains: gains are applied from the next cycle; kp outside (0, 100] is refused. */
static int on_set_gains(ln_client* clnt, ln_service_request* call, void* user)
{
    (void)clnt;
    double* kp = user;
    robot_set_gains_request_t req;
    int rc = ln_service_request_get_data(call, &req);
    if (rc != LN_OK)
        return rc;
    char message[128] = "";
    for (int j = 0; j < 7 && message[0] == '\0'; j++)
        if (!(req.kp[j] > 0.0 && req.kp[j] <= 100.0))
            snprintf(message, sizeof message, "kp[%d] = %g is outside (0, 100]", j, req.kp[j]);
    if (message[0] == '\0')
        memcpy(kp, req.kp, sizeof req.kp);
    robot_set_gains_response_t resp = {.ok = message[0] == '\0',
                                       .message_len = (uint32_t)strlen(message),
                                       .message = message};
    return ln_service_request_respond(call, &resp);
}

static void sleep_until(struct timespec* next, long period_ns)
{
    next->tv_nsec += period_ns;
    while (next->tv_nsec >= 1000000000L) {
        next->tv_nsec -= 1000000000L;
        next->tv_sec++;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, next, NULL);
}

int main(int argc, char** argv)
{
    unsigned long cycles = argc > 1 ? strtoul(argv[1], NULL, 10) : 2000;
    long period_ns = (argc > 2 ? strtol(argv[2], NULL, 10) : 1000) * 1000L;
    ln_client_options opts;
    ln_client_options_init(&opts);
    opts.argc = argc;
    opts.argv = argv;
    ln_client* clnt;
    int rc = ln_client_create(&clnt, "arm_controller", &opts);
    if (rc < 0)
        return fail("connect", rc);
    ln_outport* state_port;
    ln_inport* command_port;
    if ((rc = ln_publish(clnt, &state_port, "robot.state", ROBOT_JOINT_STATE_MD, NULL)) < 0)
        return fail("publish robot.state", rc);
    if ((rc = ln_subscribe(clnt, &command_port, "robot.command", ROBOT_COMMAND_MD, NULL)) < 0)
        return fail("subscribe robot.command", rc);
    double kp[7] = {20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0}; /* 50 ms time constant */
    ln_service_provider* gains;
    if ((rc = ln_get_service_provider(clnt, &gains, "arm.set_gains", ROBOT_SET_GAINS_SERVICE))
            < 0
        || (rc = ln_service_provider_set_handler(gains, on_set_gains, kp)) < 0
        || (rc = ln_service_provider_register(gains, "control")) < 0)
        return fail("provide arm.set_gains", rc);

    robot_joint_state_t state;
    robot_command_t command;
    memset(&state, 0, sizeof state);
    memset(&command, 0, sizeof command);
    unsigned long commands = 0;
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (unsigned long cycle = 1; cycle <= cycles; cycle++) {
        rc = ln_read(command_port, &command, sizeof command, 0, NULL); /* never waits */
        if (rc == LN_OK)
            commands++;
        else if (rc != LN_EAGAIN)
            return fail("read robot.command", rc);
        double dt = (double)period_ns * 1e-9;
        for (int j = 0; j < 7; j++) {
            double target = command.mode == 1 ? command.target[j] : state.position[j];
            double v = (target - state.position[j]) * kp[j];
            state.velocity[j] = v;
            state.position[j] += v * dt;
            state.effort[j] = 2.0 * v;
        }
        state.cycle = (uint32_t)cycle;
        state.timestamp = (double)cycle * dt;
        if ((rc = ln_write(state_port, &state, sizeof state, 0)) < 0)
            return fail("write robot.state", rc);
        /* Service calls are answered between cycles, never waiting for one. */
        if ((rc = ln_wait_and_handle_service_group_requests(clnt, "control", 0.0)) < 0)
            return fail("handle service calls", rc);
        sleep_until(&next, period_ns);
    }
    printf("arm_controller: %lu cycles, %lu commands received, joint 0 at %.3f rad\n", cycles,
           commands, state.position[0]);
    ln_client_destroy(clnt);
    return 0;
}
