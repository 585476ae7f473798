/* main.c — the pull_mcu firmware: pulls one topic (PULL_MCU_TOPIC, arm.state of the demo
 * robot by default) from an ln_daemon with libln_pull's hardened DIT (k = 3, t_max = 100 ms)
 * over SLIP frames on UART0, which the host's ln_pull_serial gateway relays to the daemon's
 * UDP pull port.  Every frame starts with its kind: 'P' an NDN packet (both ways), 'C' the
 * host's CLOCK_REALTIME in µs (u64 little-endian, gateway to firmware, 4 a second), 'T' a
 * text line (firmware to gateway).  Per sample it prints "s SEQ AGE_MS SIZE CRC32", every second a
 * "stats" line with the stack high-water mark, and after PULL_MCU_SECONDS "done". */
#include <stddef.h>
#include <stdint.h>

#include <ln/pull.h>

#include "board.h"
#include "pull_mcu_config.h"
#include "slip.h"

#define RX_BYTES 512 /* one frame: a Data packet of arm.state is about 300 bytes */
#define LINE_BYTES 120
#define DRAIN_MS 200u  /* after "done" */
#define CLOCK_FRAMES 4 /* ages from the 4th on (1 s): the first may wait while it boots */

static ln_pull_sub sub;
static uint8_t rx_buf[RX_BYTES];
static slip_rx rx;
static uint8_t line[LINE_BYTES];
static size_t line_size;
static uint64_t clock_offset_us; /* host µs - local µs: the largest of the 'C' frames */
static uint8_t clock_frames;     /* 'C' frames taken (saturates); ages from CLOCK_FRAMES on */
static uint32_t bad_frames;      /* of an unknown kind or a bad 'C' */
static uint32_t foreign;         /* packets for another name */

/* ---- output: frames and text lines ------------------------------------------------- */

static void frame(uint8_t kind, const uint8_t* data, size_t size)
{
    board_uart_putc(SLIP_END);
    slip_put(&kind, 1);
    slip_put(data, size);
    board_uart_putc(SLIP_END);
}

static const uint64_t powers_of_ten[19] = {
    1u,
    10u,
    100u,
    1000u,
    10000u,
    100000u,
    1000000u,
    10000000u,
    100000000u,
    1000000000u,
    10000000000u,
    100000000000u,
    1000000000000u,
    10000000000000u,
    100000000000000u,
    1000000000000000u,
    10000000000000000u,
    100000000000000000u,
    1000000000000000000u,
};

static void out_str(const char* s)
{
    while (*s && line_size < LINE_BYTES)
        line[line_size++] = (uint8_t)*s++;
}

static void out_u64(uint64_t v)
{
    /* by subtraction: a 64-bit division is a libgcc call on Cortex-M0+ */
    uint64_t power = 10000000000000000000u;
    int started = 0;
    for (int i = 19; i >= 0; i--) {
        char digit = '0';
        while (v >= power) {
            v -= power;
            digit++;
        }
        started |= digit != '0' || i == 0;
        if (started && line_size < LINE_BYTES)
            line[line_size++] = (uint8_t)digit;
        power = i ? powers_of_ten[i - 1] : 0u;
    }
}

static void out_i32(int32_t v)
{
    if (v < 0) {
        out_str("-");
        out_u64((uint64_t)(-(int64_t)v));
    } else {
        out_u64((uint64_t)v);
    }
}

static void out_hex32(uint32_t v)
{
    static const char hex[] = "0123456789abcdef";
    char s[9];
    for (int i = 7; i >= 0; i--, v >>= 4)
        s[i] = hex[v & 15u];
    s[8] = 0;
    out_str(s);
}

static void out_kv(const char* key, uint32_t v)
{
    out_str(key);
    out_u64(v);
}

static void out_end(void)
{
    frame('T', line, line_size);
    line_size = 0;
}

/* ---- the subscription's callbacks ----------------------------------------------------- */

/* x / 1000 for every uint32_t x, by the multiply and shift a compiler uses where the core
 * has a 32x32->64 multiply (Cortex-M0+ has none: a division would be a libgcc call). */
static uint32_t div1000(uint32_t x) { return (uint32_t)(((uint64_t)x * 0x10624DD3u) >> 38); }

static uint32_t crc32(const uint8_t* p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    while (n--) {
        c ^= *p++;
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

static void on_send(void* user, const uint8_t* packet, size_t size)
{
    (void)user;
    frame('P', packet, size);
}

static void on_data(void* user, uint64_t seq, const uint8_t* payload, size_t size,
                    uint64_t publish_us)
{
    (void)user;
    out_str("s ");
    out_u64(seq);
    out_str(" ");
    if (clock_frames >= CLOCK_FRAMES) {
        uint64_t now_us = (uint64_t)board_now_ms() * 1000u + clock_offset_us;
        int64_t age_us = (int64_t)(now_us - publish_us);
        if (age_us > INT32_MAX || age_us < -INT32_MAX) /* 36 min: a clock that is off */
            age_us = age_us < 0 ? -INT32_MAX : INT32_MAX;
        out_i32(age_us < 0 ? -(int32_t)div1000((uint32_t)-age_us)
                           : (int32_t)div1000((uint32_t)age_us));
    } else {
        out_str("-"); /* no time reference yet */
    }
    out_str(" ");
    out_u64(size);
    out_str(" ");
    out_hex32(crc32(payload, size));
    out_end();
}

/* ---- frames from the gateway ---------------------------------------------------------- */

static void on_frame(const uint8_t* f, size_t size, uint32_t now)
{
    if (f[0] == 'P') {
        if (ln_pull_receive(&sub, f + 1, size - 1, now) == 0)
            foreign++;
    } else if (f[0] == 'C' && size == 9) {
        uint64_t host_us = 0;
        for (int i = 8; i >= 1; i--)
            host_us = host_us << 8 | f[i];
        /* The frame was on its way for a while: host - local is at most the true offset,
         * and the largest seen is the best estimate (both clocks run at real time). */
        uint64_t offset = host_us - (uint64_t)now * 1000u;
        if (!clock_frames || (int64_t)(offset - clock_offset_us) > 0)
            clock_offset_us = offset;
        if (clock_frames < 255)
            clock_frames++;
    } else {
        bad_frames++;
    }
}

static void report(uint32_t now, const char* what)
{
    out_str(what);
    out_kv(" ms=", now);
    out_kv(" data=", sub.stats.data);
    out_kv(" interests=", sub.stats.interests);
    out_kv(" timeouts=", sub.stats.timeouts);
    out_kv(" nacks=", sub.stats.nacks);
    out_kv(" late=", sub.stats.late);
    out_kv(" bad=", sub.stats.bad);
    out_kv(" foreign=", foreign);
    out_kv(" frames_bad=", bad_frames + rx.oversized + rx.bad_escape);
    out_kv(" stack=", board_stack_used());
    out_end();
}

/* Reads and drops what still comes in until `until`: the gateway stops sending on "done", and
 * QEMU then ends with nothing unread on the serial socket (unread data would make the exit a
 * TCP reset, which discards the last lines on the gateway's side). */
static void drain(uint32_t until)
{
    while ((int32_t)(board_now_ms() - until) < 0) {
        while (board_uart_getc() >= 0) {
        }
        board_wait();
    }
}

int main(void)
{
    board_init();
    slip_rx_init(&rx, rx_buf, sizeof rx_buf);
    out_str("pull_mcu " PULL_MCU_TOPIC);
    out_kv(" ram data=", board_data_bytes());
    out_kv(" bss=", board_bss_bytes());
    out_kv(" stack=", board_stack_size());
    out_kv(" sub=", sizeof sub);
    out_end();

    ln_pull_options o;
    ln_pull_options_hardened(&o, PULL_MCU_DEADLINE_MS);
    uint32_t now = board_now_ms();
    int rc = ln_pull_start_name(&sub, pull_mcu_topic_name, sizeof pull_mcu_topic_name, &o, on_send,
                                on_data, NULL, NULL, now, PULL_MCU_SEED);
    if (rc < 0) {
        out_str("error: ln_pull_start_name ");
        out_i32(rc);
        out_end();
        return 1;
    }
    uint32_t poll_at = now, report_at = now + 1000u;
    const uint32_t end = now + PULL_MCU_SECONDS * 1000u;
    for (;;) {
        int c;
        now = board_now_ms();
        while ((c = board_uart_getc()) >= 0) {
            size_t size = slip_rx_byte(&rx, (uint8_t)c);
            if (size) {
                on_frame(rx_buf, size, board_now_ms());
                poll_at = now; /* a reply may have moved the next timeout */
                break;         /* one frame per round: a flood never starves the timeouts */
            }
        }
        now = board_now_ms();
        if ((int32_t)(now - poll_at) >= 0)
            poll_at = now + ln_pull_poll(&sub, now);
        if ((int32_t)(now - report_at) >= 0) {
            report_at += 1000u;
            report(now, "stats");
        }
        if ((int32_t)(now - end) >= 0) {
            report(now, "done");
            drain(now + DRAIN_MS);
            return 0;
        }
        board_wait();
    }
}
