/* arm_sensor.c — the simulated 7-joint arm of the demo robot system (robot.lnc): at a fixed
 * rate (default 1 kHz, absolute clock_nanosleep deadlines) it applies the newest torque command
 * of arm.command (robot/command, latest mode) to a rigid-joint model, integrates it and
 * publishes the result on arm.state (robot/joint_state).  Without a fresh command (none for
 * 50 ms) the joints get no torque and coast to rest.  A status line every second; SIGTERM or
 * SIGINT ends it with exit status 0.  Manager from -ln_manager or $LN_MANAGER.
 * Usage: arm_sensor [--rate HZ] */
#define _POSIX_C_SOURCE 200809L /* clock_nanosleep, sigaction */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ln/ln.h>

#include "robot_messages.h"

enum { JOINTS = 7 };
static const double INERTIA[JOINTS] = {1.2, 1.2, 0.8, 0.6, 0.3, 0.2, 0.1}; /* kg m^2 */
static const double DAMPING = 0.5;          /* Nm s/rad, viscous friction of every joint */
static const double MAX_TORQUE = 100.0;     /* Nm, the motors' limit */
static const double COMMAND_TIMEOUT = 0.05; /* s without a new command before torque off */
static const uint8_t MODE_TORQUE = 3;       /* robot/command's mode */

static volatile sig_atomic_t stop_signal;

static void on_signal(int sig) { stop_signal = sig; }

static int fail(const char* what, int rc)
{
    fprintf(stderr, "arm_sensor: %s: %s (%s)\n", what, ln_last_error(), ln_error_name(rc));
    return 1;
}

static double seconds(const struct timespec* t)
{
    return (double)t->tv_sec + (double)t->tv_nsec * 1e-9;
}

static void advance(struct timespec* t, long ns)
{
    t->tv_nsec += ns;
    while (t->tv_nsec >= 1000000000L) {
        t->tv_nsec -= 1000000000L;
        t->tv_sec++;
    }
}

static double clamp(double x, double limit) { return x > limit ? limit : x < -limit ? -limit : x; }

int main(int argc, char** argv)
{
    double rate = 1000.0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--rate") == 0 && i + 1 < argc)
            rate = strtod(argv[++i], NULL);
        else if (strcmp(argv[i], "-ln_manager") == 0 && i + 1 < argc)
            i++; /* libln's own option */
        else {
            fprintf(stderr, "usage: arm_sensor [--rate HZ] [-ln_manager HOST:PORT]\n");
            return 2;
        }
    }
    if (!(rate >= 1.0 && rate <= 10000.0)) {
        fprintf(stderr, "arm_sensor: --rate must be 1..10000 Hz\n");
        return 2;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: the sleep returns EINTR */
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);

    ln_client_options opts;
    ln_client_options_init(&opts);
    opts.argc = argc;
    opts.argv = argv;
    ln_client* clnt;
    int rc = ln_client_create(&clnt, "arm_sensor", &opts);
    if (rc < 0)
        return fail("connect", rc);
    ln_inport* command_port;
    ln_outport* state_port;
    if ((rc = ln_subscribe(clnt, &command_port, "arm.command", ROBOT_COMMAND_MD, NULL)) < 0)
        return fail("subscribe arm.command", rc);
    if ((rc = ln_publish(clnt, &state_port, "arm.state", ROBOT_JOINT_STATE_MD, NULL)) < 0)
        return fail("publish arm.state", rc);

    const long period_ns = (long)(1e9 / rate);
    const double dt = (double)period_ns * 1e-9;
    printf("publishing arm.state at %.0f Hz\n", 1.0 / dt);
    fflush(stdout);

    robot_joint_state_t state;
    robot_command_t command;
    memset(&state, 0, sizeof state);
    memset(&command, 0, sizeof command);
    double command_at = -1.0; /* arm time of the newest command, < 0: none yet */
    unsigned long commands = 0, late = 0, dropped = 0, commands_in_second = 0;
    long max_delay = 0; /* cycles from a state to the use of the command answering it */
    struct timespec start, next, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    next = start;
    for (uint32_t cycle = 1; !stop_signal; cycle++) {
        double t = (double)(cycle - 1) * dt;
        rc = ln_read(command_port, &command, sizeof command, 0, NULL); /* never waits */
        if (rc == LN_OK) {
            commands++;
            commands_in_second++;
            command_at = t;
            /* The controller stamps a command with the timestamp of the state it answers;
             * a state is published at the end of its cycle, so 1 is the shortest delay. */
            long delay = lround((t - command.timestamp) / dt) + 1;
            if (delay > max_delay)
                max_delay = delay;
        } else if (rc != LN_EAGAIN) {
            return fail("read arm.command", rc);
        }
        int driven =
            command_at >= 0.0 && t - command_at <= COMMAND_TIMEOUT && command.mode == MODE_TORQUE;
        for (int j = 0; j < JOINTS; j++) {
            double tau = driven ? clamp(command.target[j], MAX_TORQUE) : 0.0;
            double acc = (tau - DAMPING * state.velocity[j]) / INERTIA[j];
            state.velocity[j] += acc * dt; /* semi-implicit Euler */
            state.position[j] += state.velocity[j] * dt;
            state.effort[j] = tau;
        }
        state.cycle = cycle;
        state.timestamp = t + dt; /* the time the integrated state holds for */
        /* Wait a quarter period at most: the ring is locked only for a moment, e.g. while
         * the manager grows it for a new subscriber; a sample that cannot go out in time is
         * dropped and counted, the loop keeps its rate. */
        rc = ln_write(state_port, &state, sizeof state, 0.25 * dt);
        if (rc == LN_ETIMEOUT || rc == LN_EAGAIN)
            dropped++;
        else if (rc < 0)
            return fail("write arm.state", rc);

        if (cycle % (uint32_t)(1.0 / dt + 0.5) == 0) {
            char extra[64] = "";
            if (dropped > 0)
                snprintf(extra, sizeof extra, ", %lu samples dropped", dropped);
            printf("t=%.0f s, cycle %u: %lu commands in the last second, max delay "
                   "%ld cycles, %lu late cycles in all%s, q0=%+.3f rad%s\n",
                   state.timestamp, cycle, commands_in_second, max_delay, late, extra,
                   state.position[0], driven ? "" : ", no command: torque off");
            fflush(stdout);
            commands_in_second = 0;
            max_delay = 0;
        }
        advance(&next, period_ns);
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (seconds(&now) - seconds(&next) > dt) { /* more than a period behind: resync */
            late++;
            next = now;
        }
        while (!stop_signal &&
               (rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL)) != 0)
            ; /* EINTR: a signal; the loop condition sees a stop request */
    }
    printf("stopped by %s after %lu commands, %lu late cycles, %lu samples dropped\n",
           stop_signal == SIGINT ? "SIGINT" : "SIGTERM", commands, late, dropped);
    ln_client_destroy(clnt);
    return 0;
}
