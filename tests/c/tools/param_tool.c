/* param_tool.c — the C controller of the parameter tests (tests/python/parameters): a loop at
 * --rate Hz (default 1000, on absolute deadlines) around a parameter block "ctl" of every
 * kind of parameter, printing one line per parameter whose override changed at an update:
 *
 *     change UPDATE NAME VALUE       (VALUE as JSON: numbers, [lists], "strings")
 *
 * Parameters: kp double[7] (input, 0..1000), gain double (no input, default 0.5, 0..10),
 * counter uint64_t (input: the cycle number), label char[16] (no input, "init"),
 * mode int32_t (read-only 3), limits float[2] (input, -1..1).  The validator refuses
 * kp[0] == 666 and gain == 7 with a reason.  Prints "ready" once the block is registered;
 * SIGTERM/SIGINT end it.  Usage: param_tool [--rate HZ] [--block NAME] */
#define _GNU_SOURCE 1

#include <inttypes.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ln/ln.h>

static volatile sig_atomic_t stop;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static int validate(ln_parameter_block* blk, int index, const char* name, const void* value,
                    char* reason, size_t size, void* user)
{
    (void)blk;
    (void)index;
    (void)user;
    double v;
    memcpy(&v, value, sizeof v); /* kp[0] or gain: both start with a double */
    if (strcmp(name, "kp") == 0 && v == 666) {
        snprintf(reason, size, "kp[0] = 666 is the devil's gain");
        return 1;
    }
    if (strcmp(name, "gain") == 0 && v == 7) {
        snprintf(reason, size, "gain 7 is reserved");
        return 1;
    }
    return 0;
}

struct vars {
    double kp_in[7], kp[7];
    double gain;
    uint64_t counter_in, counter;
    char label[16];
    int32_t mode;
    float limits_in[2], limits[2];
};

static void print_change(const struct vars* v, const char* name, uint64_t update)
{
    printf("change %" PRIu64 " %s ", update, name);
    if (strcmp(name, "kp") == 0) {
        for (int j = 0; j < 7; j++)
            printf("%s%.17g", j ? ", " : "[", v->kp[j]);
        printf("]");
    } else if (strcmp(name, "gain") == 0) {
        printf("%.17g", v->gain);
    } else if (strcmp(name, "counter") == 0) {
        printf("%" PRIu64, v->counter);
    } else if (strcmp(name, "label") == 0) {
        printf("\"%.16s\"", v->label);
    } else if (strcmp(name, "limits") == 0) {
        printf("[%.9g, %.9g]", v->limits[0], v->limits[1]);
    }
    printf("\n");
}

int main(int argc, char** argv)
{
    double rate = 1000;
    const char* block = "ctl";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--rate") == 0)
            rate = atof(argv[i + 1]);
        else if (strcmp(argv[i], "--block") == 0)
            block = argv[i + 1];
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);

    struct vars v;
    memset(&v, 0, sizeof v);
    for (int j = 0; j < 7; j++)
        v.kp_in[j] = 100 + j;
    v.gain = 0.5;
    snprintf(v.label, sizeof v.label, "init");
    v.mode = 3;
    v.limits_in[0] = -0.5f;
    v.limits_in[1] = 0.5f;

    ln_client* clnt;
    ln_parameter_block* blk;
    if (ln_client_create(&clnt, "param_tool", NULL) != LN_OK ||
        ln_parameter_block_create(clnt, &blk, block) != LN_OK) {
        fprintf(stderr, "param_tool: %s\n", ln_last_error());
        return 1;
    }
    const ln_parameter_desc params[] = {
        {.name = "kp",
         .type = "double",
         .count = 7,
         .input = v.kp_in,
         .output = v.kp,
         .flags = LN_PARAMETER_MIN | LN_PARAMETER_MAX,
         .min = 0,
         .max = 1000,
         .description = "stiffness per joint (Nm/rad)"},
        {.name = "gain",
         .type = "double",
         .output = &v.gain,
         .flags = LN_PARAMETER_MIN | LN_PARAMETER_MAX,
         .min = 0,
         .max = 10,
         .description = "overall gain"},
        {.name = "counter",
         .type = "uint64_t",
         .input = &v.counter_in,
         .output = &v.counter,
         .description = "the cycle"},
        {.name = "label", .type = "char", .count = 16, .output = v.label},
        {.name = "mode", .type = "int32_t", .output = &v.mode, .flags = LN_PARAMETER_READ_ONLY},
        {.name = "limits",
         .type = "float",
         .count = 2,
         .input = v.limits_in,
         .output = v.limits,
         .flags = LN_PARAMETER_MIN | LN_PARAMETER_MAX,
         .min = -1,
         .max = 1},
    };
    const char* names[] = {"kp", "gain", "counter", "label", "mode", "limits"};
    for (size_t i = 0; i < sizeof params / sizeof params[0]; i++)
        if (ln_parameter_block_add(blk, &params[i]) < 0) {
            fprintf(stderr, "param_tool: %s\n", ln_last_error());
            return 1;
        }
    if (ln_parameter_block_set_validator(blk, validate, NULL) != LN_OK ||
        ln_parameter_block_register(blk) != LN_OK) {
        fprintf(stderr, "param_tool: %s\n", ln_last_error());
        return 1;
    }
    printf("ready\nservice %s\n", ln_parameter_block_service_name(blk));
    fflush(stdout);

    long period_ns = (long)(1e9 / rate);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    uint64_t updates = 0;
    while (!stop) {
        v.counter_in++;
        int changed = ln_parameter_block_update(blk);
        updates++;
        if (changed < 0) {
            fprintf(stderr, "param_tool: update failed: %d\n", changed);
            return 1;
        }
        for (int i = 0; changed > 0 && i < (int)(sizeof names / sizeof names[0]); i++)
            if (ln_parameter_block_changed(blk, i) == 1)
                print_change(&v, names[i], updates);
        if (changed > 0)
            fflush(stdout);
        next.tv_nsec += period_ns;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            next.tv_sec++;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
    }
    ln_parameter_block_destroy(blk);
    ln_client_destroy(clnt);
    printf("stopped after %" PRIu64 " updates\n", updates);
    return 0;
}
