/* startup.c — the vector table and reset code of the pull_mcu firmware: copies .data from
 * its load address, zeroes .bss, paints the unused stack with BOARD_STACK_PAINT (the
 * high-water mark is the painted words later overwritten) and runs main.  Any fault ends
 * the QEMU run with status 1. */
#include <stdint.h>

#include "board.h"

extern uint32_t __data_load[], __data_start[], __data_end[], __bss_start[], __bss_end[];
extern uint32_t __stack_bottom[], __stack_top[];

int main(void);
void Reset_Handler(void);
void SysTick_Handler(void);
void UART0RX_Handler(void);

static void fault(void) { board_exit(1); }

void Reset_Handler(void)
{
    const uint32_t* src = __data_load;
    for (uint32_t* dst = __data_start; dst < __data_end;)
        *dst++ = *src++;
    for (uint32_t* dst = __bss_start; dst < __bss_end;)
        *dst++ = 0u;
    uint32_t* sp;
    __asm volatile("mov %0, sp" : "=r"(sp));
    for (uint32_t* p = __stack_bottom; p < sp - 8; p++) /* 32 bytes below sp: this frame */
        *p = BOARD_STACK_PAINT;
    board_exit(main());
}

/* Cortex-M3 system exceptions, then the AN385's IRQ 0 (UART0 RX). */
__attribute__((section(".vectors"), used)) static void (*const vectors[])(void) = {
    (void (*)(void))(uintptr_t)__stack_top,
    Reset_Handler,
    fault, /* NMI */
    fault, /* HardFault */
    fault, /* MemManage */
    fault, /* BusFault */
    fault, /* UsageFault */
    0,
    0,
    0,
    0,
    fault, /* SVCall */
    fault, /* DebugMonitor */
    0,
    fault, /* PendSV */
    SysTick_Handler,
    UART0RX_Handler,
};
