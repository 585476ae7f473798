/* slip.c — the SLIP (RFC 1055) decoder and encoder of slip.h; the encoder writes to UART0. */
#include "slip.h"

#include "board.h"

enum { IN_FRAME, AFTER_ESC, DROPPING };

void slip_rx_init(slip_rx* rx, uint8_t* buf, size_t cap)
{
    rx->buf = buf;
    rx->cap = cap;
    rx->size = 0;
    rx->state = IN_FRAME;
    rx->oversized = rx->bad_escape = 0;
}

size_t slip_rx_byte(slip_rx* rx, uint8_t c)
{
    if (c == SLIP_END) {
        size_t size = rx->state == IN_FRAME ? rx->size : 0;
        if (rx->state == AFTER_ESC)
            rx->bad_escape++;
        rx->size = 0;
        rx->state = IN_FRAME;
        return size;
    }
    if (rx->state == DROPPING)
        return 0;
    if (rx->state == AFTER_ESC) {
        if (c != SLIP_ESC_END && c != SLIP_ESC_ESC) {
            rx->bad_escape++;
            rx->state = DROPPING;
            return 0;
        }
        c = c == SLIP_ESC_END ? SLIP_END : SLIP_ESC;
        rx->state = IN_FRAME;
    } else if (c == SLIP_ESC) {
        rx->state = AFTER_ESC;
        return 0;
    }
    if (rx->size == rx->cap) {
        rx->oversized++;
        rx->state = DROPPING;
        return 0;
    }
    rx->buf[rx->size++] = c;
    return 0;
}

void slip_put(const uint8_t* data, size_t size)
{
    for (size_t i = 0; i < size; i++) {
        if (data[i] == SLIP_END) {
            board_uart_putc(SLIP_ESC);
            board_uart_putc(SLIP_ESC_END);
        } else if (data[i] == SLIP_ESC) {
            board_uart_putc(SLIP_ESC);
            board_uart_putc(SLIP_ESC_ESC);
        } else {
            board_uart_putc(data[i]);
        }
    }
}
