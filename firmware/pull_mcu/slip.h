/* slip.h — SLIP framing (RFC 1055) of the serial link between the pull_mcu firmware and the
 * ln_pull_serial gateway: END (0xC0) closes a frame, ESC (0xDB) escapes END and ESC.  The
 * decoder takes one byte at a time into a caller-owned buffer; an oversized frame or a bad
 * escape is dropped whole and counted, and decoding goes on at the next END. */
#ifndef PULL_MCU_SLIP_H
#define PULL_MCU_SLIP_H

#include <stddef.h>
#include <stdint.h>

#define SLIP_END 0xC0u
#define SLIP_ESC 0xDBu
#define SLIP_ESC_END 0xDCu
#define SLIP_ESC_ESC 0xDDu

typedef struct slip_rx {
    uint8_t* buf;
    size_t cap;
    size_t size;
    uint8_t state;       /* 0: in a frame, 1: after ESC, 2: dropping until END */
    uint32_t oversized;  /* frames dropped: longer than cap */
    uint32_t bad_escape; /* frames dropped: ESC followed by neither ESC_END nor ESC_ESC */
} slip_rx;

void slip_rx_init(slip_rx* rx, uint8_t* buf, size_t cap);
/* Takes one byte; returns the size of the frame it completed (in rx->buf), else 0.  Empty
 * frames (END END) are not reported. */
size_t slip_rx_byte(slip_rx* rx, uint8_t c);

/* Writes the bytes of one frame part to the UART, escaped (no END). */
void slip_put(const uint8_t* data, size_t size);

#endif
