/* board.h — the little the pull_mcu firmware needs of the MPS2 AN385 board: the ms clock (a
 * free-running timer), UART0 polled (an RX interrupt only wakes the core from WFI), the
 * stack high-water mark from the paint of startup.c, the RAM the linker placed, and the
 * semihosting exit that ends the QEMU run. */
#ifndef PULL_MCU_BOARD_H
#define PULL_MCU_BOARD_H

#include <stddef.h>
#include <stdint.h>

#define BOARD_STACK_PAINT 0xA5A5A5A5u /* the word startup.c fills the unused stack with */

void board_init(void);
uint32_t board_now_ms(void);
/* The next received byte, or -1 if none is waiting. */
int board_uart_getc(void);
void board_uart_putc(uint8_t c);
/* Sleeps until an interrupt (the 1 ms tick or a received byte). */
void board_wait(void);
/* Bytes of the stack ever used (the painted words overwritten), and its size. */
uint32_t board_stack_used(void);
uint32_t board_stack_size(void);
/* Bytes of .data and .bss as linked. */
uint32_t board_data_bytes(void);
uint32_t board_bss_bytes(void);
/* Ends the run through semihosting (QEMU exits with 0 for status 0, 1 otherwise). */
void board_exit(int status) __attribute__((noreturn));

#endif
