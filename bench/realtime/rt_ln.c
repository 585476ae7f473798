/* rt_ln.c — the links_and_nodes side of bench/realtime: a periodic ping-pong through two libln
 * topics (ln_write / blocking ln_read, default spin_us), ping timed on absolute deadlines
 * (rt_common.h).  Shapes: pingpong (64 B both ways) or control (robot/joint_state out on
 * NAME.state, robot/command back on NAME.command, as the demo robot's arm and controller).
 * Manager from $LN_MANAGER. */
#include <ln/ln.h>

#include "rt_common.h"

static const char usage[] =
    "usage: rt_ln ping NAME pingpong|control RATE_HZ COUNT WARMUP OUT\n"
    "       rt_ln pong NAME pingpong|control TOTAL WARMUP\n"
    "ping writes COUNT (round trip ns, wake-up lateness ns) pairs to OUT; each side prints a\n"
    "JSON line of how it ran (policy, priority, CPUs, mlockall, minor faults).\n";

typedef struct ends {
    ln_client* clnt;
    ln_outport* pub;
    ln_inport* sub;
    unsigned char buf[RT_MAX_SIZE];
} ends;

static void fail(const char* what, int rc)
{
    fprintf(stderr, "rt_ln: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    exit(2);
}

static void send_one(void* ctx, uint64_t counter, size_t size)
{
    ends* e = ctx;
    memcpy(e->buf, &counter, sizeof counter);
    int rc = ln_write(e->pub, e->buf, size, -1);
    if (rc < 0)
        fail("ln_write", rc);
}

static uint64_t receive_one(void* ctx, size_t size)
{
    ends* e = ctx;
    int rc = ln_read(e->sub, e->buf, size, -1, NULL);
    if (rc < 0)
        fail("ln_read", rc);
    uint64_t counter;
    memcpy(&counter, e->buf, sizeof counter);
    return counter;
}

static void open_ends(ends* e, const char* name, int ping, int control)
{
    char out[256], in[256];
    const char* down = control ? "state" : "ping";
    const char* up = control ? "command" : "pong";
    snprintf(out, sizeof out, "%s.%s", name, ping ? down : up);
    snprintf(in, sizeof in, "%s.%s", name, ping ? up : down);
    const char* small = LNBENCH_SAMPLE_64_MD_NAME;
    uint64_t small_hash = LNBENCH_SAMPLE_64_LAYOUT_HASH;
    const char* md_down = control ? ROBOT_JOINT_STATE_MD_NAME : small;
    const char* md_up = control ? ROBOT_COMMAND_MD_NAME : small;
    uint64_t h_down = control ? ROBOT_JOINT_STATE_LAYOUT_HASH : small_hash;
    uint64_t h_up = control ? ROBOT_COMMAND_LAYOUT_HASH : small_hash;
    size_t s_down = control ? sizeof(robot_joint_state_t) : sizeof(lnbench_sample_64_t);
    size_t s_up = control ? sizeof(robot_command_t) : sizeof(lnbench_sample_64_t);
    int rc = ln_client_create(&e->clnt, ping ? "rt_ln_ping" : "rt_ln_pong", NULL);
    if (rc < 0)
        fail("ln_client_create", rc);
    rc = ln_publish(e->clnt, &e->pub, out, ping ? md_down : md_up, ping ? h_down : h_up,
                    ping ? s_down : s_up, NULL);
    if (rc < 0)
        fail("ln_publish", rc);
    rc = ln_subscribe(e->clnt, &e->sub, in, ping ? md_up : md_down, ping ? h_up : h_down,
                      ping ? s_up : s_down, NULL);
    if (rc < 0)
        fail("ln_subscribe", rc);
}

int main(int argc, char** argv)
{
    int ping = argc == 8 && strcmp(argv[1], "ping") == 0;
    if (!ping && !(argc == 6 && strcmp(argv[1], "pong") == 0)) {
        fputs(usage, stderr);
        return 2;
    }
    rt_shape shape = rt_shape_of(argv[3]);
    static ends e; /* the buffer stays off the stack */
    open_ends(&e, argv[2], ping, strcmp(shape.name, "control") == 0);
    rt_ops ops = {send_one, receive_one};
    int rc =
        ping ? rt_ping(&ops, &e, &shape, atof(argv[4]), strtoull(argv[5], NULL, 10),
                       strtoull(argv[6], NULL, 10), argv[7])
             : rt_pong(&ops, &e, &shape, strtoull(argv[4], NULL, 10), strtoull(argv[5], NULL, 10));
    ln_client_destroy(e.clnt);
    return rc;
}
