/* board.c — MPS2 AN385 (Cortex-M3, as QEMU emulates it) for the pull_mcu firmware: the ms
 * clock from the free-running CMSDK timer 0 (25 MHz; counting SysTick interrupts would lose
 * time whenever the emulator's thread is descheduled for more than a tick), SysTick at 1 kHz
 * only to wake the core, the CMSDK APB UART0 at 0x40004000 read and written by polling, its
 * RX interrupt (IRQ 0) enabled only so that WFI wakes on a byte, and semihosting SYS_EXIT. */
#include "board.h"

#define REG(addr) (*(volatile uint32_t*)(addr))

#define CORE_HZ 25000000u
#define SYST_CSR REG(0xE000E010u)
#define SYST_RVR REG(0xE000E014u)
#define SYST_CVR REG(0xE000E018u)
#define NVIC_ISER0 REG(0xE000E100u)

#define TIMER0 0x40000000u /* counts down from 0xFFFFFFFF at the core clock, wrapping */
#define TIMER_CTRL REG(TIMER0 + 0x0u)
#define TIMER_VALUE REG(TIMER0 + 0x4u)
#define TIMER_RELOAD REG(TIMER0 + 0x8u)
#define CYCLES_PER_MS (CORE_HZ / 1000u)

#define UART0 0x40004000u
#define UART_DATA REG(UART0 + 0x00u)
#define UART_STATE REG(UART0 + 0x04u) /* bit 0: TX full, bit 1: RX full */
#define UART_CTRL REG(UART0 + 0x08u)  /* bit 0: TX on, bit 1: RX on, bit 3: RX interrupt */
#define UART_INTSTATUS REG(UART0 + 0x0Cu)
#define UART_BAUDDIV REG(UART0 + 0x10u)
#define UART_IRQ 0u /* UART0 RX on the AN385 */

extern uint32_t __data_start[], __data_end[], __bss_start[], __bss_end[];
extern uint32_t __stack_bottom[], __stack_top[];

static uint32_t clock_ms, clock_cycles, clock_last; /* main loop only */

/* SysTick only wakes the core from WFI. */
void SysTick_Handler(void) {}

/* Acknowledges a received byte; the main loop reads it. */
void UART0RX_Handler(void) { UART_INTSTATUS = 2u; }

void board_init(void)
{
    UART_BAUDDIV = CORE_HZ / 115200u;
    UART_CTRL = 1u | 2u | 8u;
    NVIC_ISER0 = 1u << UART_IRQ;
    TIMER_RELOAD = 0xFFFFFFFFu;
    TIMER_VALUE = 0xFFFFFFFFu;
    TIMER_CTRL = 1u;
    clock_last = TIMER_VALUE;
    SYST_RVR = CYCLES_PER_MS - 1u;
    SYST_CVR = 0u;
    SYST_CSR = 7u; /* core clock, interrupt, on */
}

uint32_t board_now_ms(void)
{
    uint32_t value = TIMER_VALUE;
    clock_cycles += clock_last - value; /* called far more often than every 171 s */
    clock_last = value;
    while (clock_cycles >= CYCLES_PER_MS) { /* no division: a libgcc call on Cortex-M0+ */
        clock_cycles -= CYCLES_PER_MS;
        clock_ms++;
    }
    return clock_ms;
}

int board_uart_getc(void)
{
    if (!(UART_STATE & 2u))
        return -1;
    return (int)(UART_DATA & 0xFFu);
}

void board_uart_putc(uint8_t c)
{
    while (UART_STATE & 1u) {
    }
    UART_DATA = c;
}

void board_wait(void)
{
    __asm volatile("cpsid i" ::: "memory");
    if (!(UART_STATE & 2u)) /* no byte arrived since the last look: sleep */
        __asm volatile("wfi" ::: "memory");
    __asm volatile("cpsie i" ::: "memory");
}

uint32_t board_stack_used(void)
{
    const uint32_t* p = __stack_bottom;
    while (p < __stack_top && *p == BOARD_STACK_PAINT)
        p++;
    return (uint32_t)((uintptr_t)__stack_top - (uintptr_t)p);
}

uint32_t board_stack_size(void)
{
    return (uint32_t)((uintptr_t)__stack_top - (uintptr_t)__stack_bottom);
}

uint32_t board_data_bytes(void)
{
    return (uint32_t)((uintptr_t)__data_end - (uintptr_t)__data_start);
}

uint32_t board_bss_bytes(void) { return (uint32_t)((uintptr_t)__bss_end - (uintptr_t)__bss_start); }

void board_exit(int status)
{
    /* SYS_EXIT (0x18) with ADP_Stopped_ApplicationExit (0x20026), or RunTimeErrorUnknown */
    register uint32_t op __asm("r0") = 0x18u;
    register uint32_t reason __asm("r1") = status == 0 ? 0x20026u : 0x20023u;
    __asm volatile("bkpt 0xAB" : : "r"(op), "r"(reason) : "memory");
    for (;;) {
    }
}
