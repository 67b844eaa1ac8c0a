/* Minimal start-up of the C example on a Cortex-M4F under QEMU (netduinoplus2, an
 * STM32F405): vector table, FPU on, .bss zeroed, semihosting (newlib's rdimon) for printf
 * and the exit status. .data is loaded in place by QEMU's ELF loader (link.ld keeps its load
 * address in RAM), which is enough for an emulator test; a board would copy it from flash.
 * With -DGA_STACK_PAINT the free stack is painted before main and its high-water mark is
 * printed at the end.
 * SPDX-License-Identifier: MIT OR Apache-2.0 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

extern int main(void);
extern void initialise_monitor_handles(void);
extern uint32_t __bss_start__, __bss_end__, __stack_top, __stack_limit;

#define PAINT 0xCCCCCCCCu
#define CPACR (*(volatile uint32_t *)0xE000ED88u)

void Reset_Handler(void);
void Fault_Handler(void);

__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&__stack_top), Reset_Handler, Fault_Handler, Fault_Handler,
    Fault_Handler, Fault_Handler, Fault_Handler, 0, 0, 0, 0, Fault_Handler, Fault_Handler, 0,
    Fault_Handler, Fault_Handler,
};

void Fault_Handler(void) {
  /* a fault (or the library's panic handler, `udf`) ends the run with failure */
  exit(3);
}

#ifdef GA_STACK_PAINT
static void paint_stack(void) {
  uint32_t sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (volatile uint32_t *p = &__stack_limit; (uint32_t)p < sp - 64u; p++) *p = PAINT;
}

static void report_stack(void) {
  uint32_t *p = &__stack_limit;
  while (p < &__stack_top && *p == PAINT) p++;
  printf("stack: high-water %u B of %u B (main and every call)\n",
         (unsigned)((uint32_t)&__stack_top - (uint32_t)p),
         (unsigned)((uint32_t)&__stack_top - (uint32_t)&__stack_limit));
}
#endif

__attribute__((noreturn)) void Reset_Handler(void) {
  CPACR |= 0xFu << 20; /* CP10, CP11: full access to the FPU */
  __asm__ volatile("dsb\n isb" ::: "memory");
  for (uint32_t *p = &__bss_start__; p < &__bss_end__; p++) *p = 0;
  initialise_monitor_handles();
#ifdef GA_STACK_PAINT
  paint_stack();
#endif
  int rc = main();
#ifdef GA_STACK_PAINT
  report_stack();
#endif
  fflush(stdout);
  exit(rc);
}
