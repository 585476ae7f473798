/* joint_state_demo.c — fills a generated robot_joint_state_t for a simulated 7-axis arm over
 * a few controller cycles and prints it with the md's signature and layout hash.
 * Shows the build side of a client: generated header, libln version check, error strings. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>

#include <ln/ln.h>

#include "robot_messages.h"

enum { AXES = 7, CYCLES = 3 };
static const double CYCLE_TIME = 0.001; /* s, a 1 kHz controller */
static const double PI = 3.14159265358979323846;

/* A smooth motion per axis: each joint swings with its own amplitude and frequency. */
static void simulate(robot_joint_state_t* state, uint32_t cycle)
{
    state->cycle = cycle;
    state->timestamp = cycle * CYCLE_TIME;
    for (int axis = 0; axis < AXES; axis++) {
        double amplitude = 0.1 * (axis + 1);           /* rad */
        double omega = 2.0 * PI * (0.5 + 0.25 * axis); /* rad/s */
        double t = state->timestamp;
        state->position[axis] = amplitude * sin(omega * t);
        state->velocity[axis] = amplitude * omega * cos(omega * t);
        state->effort[axis] = -5.0 * state->position[axis]; /* a spring at each joint */
    }
}

static void print_row(const char* label, const double* values)
{
    printf("  %-9s", label);
    for (int axis = 0; axis < AXES; axis++)
        printf(" %8.4f", values[axis]);
    printf("\n");
}

int main(void)
{
    int rc = LN_VERSION_CHECK();
    if (rc != LN_OK) {
        fprintf(stderr, "libln %s cannot serve this program (built with %s): %s\n", ln_version(),
                LN_VERSION_STRING, ln_strerror(rc));
        return 1;
    }
    printf("libln %s\n", ln_version());
    printf("md %s: %d bytes, layout hash %016" PRIx64 "\n  signature %s\n",
           ROBOT_JOINT_STATE_MD_NAME, (int)ROBOT_JOINT_STATE_SIZE,
           (uint64_t)ROBOT_JOINT_STATE_LAYOUT_HASH, ROBOT_JOINT_STATE_SIGNATURE);

    robot_joint_state_t state = {0};
    for (uint32_t cycle = 1; cycle <= CYCLES; cycle++) {
        simulate(&state, cycle);
        /* Copies, because the struct is packed and its arrays may be unaligned. */
        double position[AXES], velocity[AXES], effort[AXES];
        for (int axis = 0; axis < AXES; axis++) {
            position[axis] = state.position[axis];
            velocity[axis] = state.velocity[axis];
            effort[axis] = state.effort[axis];
        }
        printf("cycle %" PRIu32 " at t=%.3f s\n", state.cycle, state.timestamp);
        print_row("position", position);
        print_row("velocity", velocity);
        print_row("effort", effort);
    }
    return 0;
}
