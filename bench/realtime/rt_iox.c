/* rt_iox.c — the iceoryx (C binding) side of bench/realtime: the same periodic ping-pong as
 * rt_ln (rt_common.h), the message copied into a loaned chunk and out of a taken one; waiting
 * spins (sched_yield) SPIN_US as libln's spin_us, then sleeps in a WaitSet.  Needs a running
 * iox-roudi with a mempool for the sizes; built only where the iceoryx headers are installed. */
#include <stdbool.h>
#include <unistd.h>

#include "iceoryx_binding_c/chunk.h"
#include "iceoryx_binding_c/log.h"
#include "iceoryx_binding_c/publisher.h"
#include "iceoryx_binding_c/runtime.h"
#include "iceoryx_binding_c/subscriber.h"
#include "iceoryx_binding_c/wait_set.h"

#include "iox_take.h"
#include "rt_common.h"

static const char usage[] =
    "usage: rt_iox ping NAME pingpong|control RATE_HZ COUNT WARMUP OUT SPIN_US\n"
    "       rt_iox pong NAME pingpong|control TOTAL WARMUP SPIN_US\n";

typedef struct port {
    iox_pub_storage_t pub_storage;
    iox_sub_storage_t sub_storage;
    iox_ws_storage_t ws_storage;
    iox_pub_t pub;
    iox_sub_t sub;
    iox_ws_t ws;
    uint64_t spin_ns;
    unsigned char buf[RT_MAX_SIZE];
} port;

static void open_ports(port* p, const char* out, const char* in)
{
    iox_pub_options_t po;
    iox_pub_options_init(&po);
    po.historyCapacity = 0;
    p->pub = iox_pub_init(&p->pub_storage, "lnbench", "rt", out, &po);
    iox_sub_options_t so;
    iox_sub_options_init(&so);
    so.queueCapacity = 4;
    so.historyRequest = 0;
    p->sub = iox_sub_init(&p->sub_storage, "lnbench", "rt", in, &so);
    p->ws = iox_ws_init(&p->ws_storage);
    if (iox_ws_attach_subscriber_state(p->ws, p->sub, SubscriberState_HAS_DATA, 0, NULL) !=
        WaitSetResult_SUCCESS) {
        fputs("rt_iox: cannot attach the subscriber to a WaitSet\n", stderr);
        exit(2);
    }
}

static void send_one(void* ctx, uint64_t counter, size_t size)
{
    port* p = ctx;
    void* chunk;
    enum iox_AllocationResult rc = iox_pub_loan_chunk(p->pub, &chunk, (uint32_t)size);
    if (rc != AllocationResult_SUCCESS) {
        fprintf(stderr, "rt_iox: iox_pub_loan_chunk of %zu bytes failed (%d)\n", size, (int)rc);
        exit(2);
    }
    memcpy(p->buf, &counter, sizeof counter);
    memcpy(chunk, p->buf, size);
    iox_pub_publish_chunk(p->pub, chunk);
}

static uint64_t receive_one(void* ctx, size_t size)
{
    port* p = ctx;
    const void* chunk;
    while (!(chunk = iox_take_chunk(p->sub, p->ws, p->spin_ns, 60.0, "rt_iox")))
        continue; /* 60 s without a chunk: wait on */
    memcpy(p->buf, chunk, size);
    iox_sub_release_chunk(p->sub, chunk);
    uint64_t counter;
    memcpy(&counter, p->buf, sizeof counter);
    return counter;
}

static void wait_connected(const port* p)
{
    while (iox_sub_get_subscription_state(p->sub) != SubscribeState_SUBSCRIBED ||
           !iox_pub_has_subscribers(p->pub))
        nanosleep(&(struct timespec){0, 1000000}, NULL);
}

int main(int argc, char** argv)
{
    int ping = argc == 9 && strcmp(argv[1], "ping") == 0;
    if (!ping && !(argc == 7 && strcmp(argv[1], "pong") == 0)) {
        fputs(usage, stderr);
        return 2;
    }
    rt_shape shape = rt_shape_of(argv[3]);
    int control = strcmp(shape.name, "control") == 0;
    char out[100], in[100], name[64];
    snprintf(out, sizeof out, "%s.%s", argv[2],
             ping ? (control ? "state" : "ping") : (control ? "command" : "pong"));
    snprintf(in, sizeof in, "%s.%s", argv[2],
             ping ? (control ? "command" : "pong") : (control ? "state" : "ping"));
    snprintf(name, sizeof name, "rt_iox_%s_%d", argv[1], (int)getpid());
    iox_set_loglevel(Iceoryx_LogLevel_Warn); /* stdout is for the driver */
    iox_runtime_init(name);
    static port p; /* the storages are large */
    p.spin_ns = strtoull(argv[argc - 1], NULL, 10) * 1000u;
    open_ports(&p, out, in);
    rt_ops ops = {send_one, receive_one};
    int rc;
    if (ping) {
        wait_connected(&p);
        rc = rt_ping(&ops, &p, &shape, atof(argv[4]), strtoull(argv[5], NULL, 10),
                     strtoull(argv[6], NULL, 10), argv[7]);
    } else {
        rc = rt_pong(&ops, &p, &shape, strtoull(argv[4], NULL, 10), strtoull(argv[5], NULL, 10));
    }
    iox_ws_deinit(p.ws);
    iox_sub_deinit(p.sub);
    iox_pub_deinit(p.pub);
    iox_runtime_shutdown();
    return rc;
}
