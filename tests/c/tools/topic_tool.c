/* topic_tool.c — a C publisher/subscriber driven by the Python topic tests (cross-language
 * and crash tests).  The manager comes from $LN_MANAGER.
 *   topic_tool pub-joint TOPIC COUNT            robot/joint_state samples with values from i
 *   topic_tool sub-joint TOPIC COUNT TIMEOUT    print "cycle timestamp pos0..6" per sample
 *   topic_tool pub-pattern TOPIC COUNT|0 [wait|nowait [FIRST]]   pattern samples with values
 *                                   FIRST, FIRST+1, ... (0: forever, for kill tests)
 *   topic_tool sub-pattern TOPIC COUNT BUFFERS TIMEOUT [STOP]   count, check order and tearing;
 *                                   stops early at a sample whose value is STOP
 *   topic_tool pub-loop TOPIC PERIOD_US   robot/joint_state with cycle 1, 2, ... every PERIOD_US
 *                                   forever, never calling the manager after publishing (the
 *                                   manager restart tests); "ready" after the first sample */
#define _POSIX_C_SOURCE 200809L /* nanosleep */

#include <inttypes.h>
#include <stdio.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>

#include <ln/ln.h>

#include "topic_messages.h"

static int fail(const char* what, int rc)
{
    fprintf(stderr, "topic_tool: %s: %s: %s\n", what, ln_error_name(rc), ln_last_error());
    return 2;
}

static void fill_joint(robot_joint_state_t* js, uint64_t i)
{
    memset(js, 0, sizeof(*js));
    js->timestamp = (double)i * 0.001;
    js->cycle = (uint32_t)i;
    for (int j = 0; j < 7; j++) {
        js->position[j] = (double)i + j / 8.0;
        js->velocity[j] = -(double)i - j / 4.0;
        js->effort[j] = (double)(i * j);
    }
}

static int pub_joint(ln_client* c, const char* topic, uint64_t count)
{
    ln_outport* p;
    int rc = ln_publish(c, &p, topic, ROBOT_JOINT_STATE_MD, NULL);
    if (rc < 0)
        return fail("publish", rc);
    printf("ready\n");
    fflush(stdout);
    robot_joint_state_t js;
    for (uint64_t i = 1; i <= count; i++) {
        fill_joint(&js, i);
        if ((rc = ln_write(p, &js, sizeof js, -1)) < 0)
            return fail("write", rc);
    }
    return 0;
}

static int sub_joint(ln_client* c, const char* topic, uint64_t count, double timeout)
{
    ln_inport* s;
    ln_port_options o;
    ln_port_options_init(&o);
    o.buffers = 1024;
    int rc = ln_subscribe(c, &s, topic, ROBOT_JOINT_STATE_MD, &o);
    if (rc < 0)
        return fail("subscribe", rc);
    printf("ready\n");
    fflush(stdout);
    robot_joint_state_t js;
    for (uint64_t n = 0; n < count; n++) {
        if ((rc = ln_read(s, &js, sizeof js, timeout, NULL)) < 0)
            return fail("read", rc);
        printf("%" PRIu32 " %.17g", js.cycle, js.timestamp);
        for (int j = 0; j < 7; j++)
            printf(" %.17g %.17g %.17g", js.position[j], js.velocity[j], js.effort[j]);
        printf("\n");
    }
    fflush(stdout);
    return 0;
}

static int pub_pattern(ln_client* c, const char* topic, uint64_t count, int wait, uint64_t first)
{
    ln_outport* p;
    ln_port_options o;
    ln_port_options_init(&o);
    o.flags = wait ? LN_PUBLISH_WAIT_FOR_SUBSCRIBERS : 0;
    int rc = ln_publish(c, &p, topic, LNTEST_PATTERN_MD, &o);
    if (rc < 0)
        return fail("publish", rc);
    printf("ready\n");
    fflush(stdout);
    for (uint64_t i = 1; count == 0 || i <= count; i++) {
        void* slot;
        if ((rc = ln_write_loan(p, &slot, -1)) < 0)
            return fail("loan", rc);
        lntest_pattern_t* m = slot;
        for (int k = 0; k < 512; k++)
            m->word[k] = first + i - 1;
        if ((rc = ln_write_commit(p)) < 0)
            return fail("commit", rc);
    }
    return 0;
}

static int pub_loop(ln_client* c, const char* topic, uint64_t period_us)
{
    ln_outport* p;
    int rc = ln_publish(c, &p, topic, ROBOT_JOINT_STATE_MD, NULL);
    if (rc < 0)
        return fail("publish", rc);
    robot_joint_state_t js;
    struct timespec pause = {(time_t)(period_us / 1000000), (long)(period_us % 1000000) * 1000};
    for (uint64_t i = 1;; i++) {
        fill_joint(&js, i);
        if ((rc = ln_write(p, &js, sizeof js, -1)) < 0)
            return fail("write", rc);
        if (i == 1) {
            printf("ready\n");
            fflush(stdout);
        }
        nanosleep(&pause, NULL);
    }
}

static int sub_pattern(ln_client* c, const char* topic, uint64_t count, uint32_t buffers,
                       double timeout, uint64_t stop)
{
    ln_inport* s;
    ln_port_options o;
    ln_port_options_init(&o);
    o.buffers = buffers;
    int rc = ln_subscribe(c, &s, topic, LNTEST_PATTERN_MD, &o);
    if (rc < 0)
        return fail("subscribe", rc);
    printf("ready\n");
    fflush(stdout);
    static lntest_pattern_t m;
    uint64_t got = 0, torn = 0, disorder = 0, last_seq = 0, timeouts = 0, value = 0;
    ln_sample_info info;
    while (got < count) {
        rc = ln_read(s, &m, sizeof m, timeout, &info);
        if (rc == LN_ETIMEOUT) {
            timeouts++;
            break;
        }
        if (rc < 0)
            return fail("read", rc);
        got++;
        for (int k = 1; k < 512; k++)
            if (m.word[k] != m.word[0]) {
                torn++;
                break;
            }
        if (info.seq <= last_seq)
            disorder++;
        last_seq = info.seq;
        value = m.word[0];
        if (stop && value == stop)
            break;
    }
    printf("received %" PRIu64 " torn %" PRIu64 " disorder %" PRIu64 " overruns %" PRIu64
           " timeouts %" PRIu64 " last %" PRIu64 " value %" PRIu64 "\n",
           got, torn, disorder, ln_inport_overruns(s), timeouts, last_seq, value);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: see the top of topic_tool.c\n");
        return 2;
    }
    ln_client* c;
    int rc = ln_client_create(&c, "topic_tool", NULL);
    if (rc < 0)
        return fail("client", rc);
    const char* mode = argv[1];
    const char* topic = argv[2];
    uint64_t count = strtoull(argv[3], NULL, 10);
    if (!strcmp(mode, "pub-joint"))
        rc = pub_joint(c, topic, count);
    else if (!strcmp(mode, "sub-joint") && argc > 4)
        rc = sub_joint(c, topic, count, atof(argv[4]));
    else if (!strcmp(mode, "pub-pattern"))
        rc = pub_pattern(c, topic, count, argc > 4 && !strcmp(argv[4], "wait"),
                         argc > 5 ? strtoull(argv[5], NULL, 10) : 1);
    else if (!strcmp(mode, "pub-loop"))
        rc = pub_loop(c, topic, count);
    else if (!strcmp(mode, "sub-pattern") && argc > 5)
        rc = sub_pattern(c, topic, count, (uint32_t)atoi(argv[4]), atof(argv[5]),
                         argc > 6 ? strtoull(argv[6], NULL, 10) : 0);
    else {
        fprintf(stderr, "topic_tool: bad arguments\n");
        rc = 2;
    }
    ln_client_destroy(c);
    return rc;
}
