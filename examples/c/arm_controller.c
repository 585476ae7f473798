/* arm_controller.c — a simulated 7-axis arm controller: every cycle it reads the newest
 * robot/command (latest mode), moves its joints toward the target with a first-order lag,
 * and publishes robot/joint_state.  The manager comes from -ln_manager or $LN_MANAGER.
 * Usage: arm_controller [CYCLES] [PERIOD_US] */
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
            double v = (target - state.position[j]) * 20.0; /* 50 ms time constant */
            state.velocity[j] = v;
            state.position[j] += v * dt;
            state.effort[j] = 2.0 * v;
        }
        state.cycle = (uint32_t)cycle;
        state.timestamp = (double)cycle * dt;
        if ((rc = ln_write(state_port, &state, sizeof state, 0)) < 0)
            return fail("write robot.state", rc);
        sleep_until(&next, period_ns);
    }
    printf("arm_controller: %lu cycles, %lu commands received, joint 0 at %.3f rad\n", cycles,
           commands, state.position[0]);
    ln_client_destroy(clnt);
    return 0;
}
