/*
 * Start-up for the MPS2 AN386 (Cortex-M4F): the vector table, then enable the FPU, copy
 * .data, zero .bss, run main() and leave QEMU through semihosting with its result.
 */
#include <stdint.h>

#include "semihosting.h"

extern uint32_t __data_start[], __data_end[], __data_load[], __bss_start[], __bss_end[];
extern uint32_t __stack_top[];

int main(void);

void reset_handler(void);
void fault_handler(void);
void systick_handler(void);

/* Initial stack pointer, reset, NMI, hard fault, memory management, bus and usage faults,
   and SysTick (entry 15). A program may define its own fault and SysTick handlers (these are
   weak): corrupt.c does. */
__attribute__((section(".vectors"), used)) static const uintptr_t vectors[16] = {
    (uintptr_t)__stack_top,
    (uintptr_t)reset_handler,
    (uintptr_t)fault_handler,
    (uintptr_t)fault_handler,
    (uintptr_t)fault_handler,
    (uintptr_t)fault_handler,
    (uintptr_t)fault_handler,
    [15] = (uintptr_t)systick_handler,
};

void reset_handler(void) {
    /* Full access to the FPU (CP10, CP11 in SCB->CPACR) before any floating-point
       instruction: the code is built for -mfloat-abi=hard. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    for (uint32_t *src = __data_load, *dst = __data_start; dst < __data_end;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = __bss_start; dst < __bss_end;) {
        *dst++ = 0;
    }
    semihosting_exit(main() == 0);
}

__attribute__((weak)) void fault_handler(void) {
    semihosting_write0("error: fault\n");
    semihosting_exit(0);
}

/* SysTick's interrupt is never enabled but by a program that defines its own handler. */
__attribute__((weak)) void systick_handler(void) {}
