"""Bare-metal sources around the stage for the Cortex-M4F measurements (QEMU mps2-an386).

* ``startup.c``: vector table, reset handler (copies .data, zeroes .bss, paints the
  stack with a pattern for the high-water mark, enables the FPU), semihosting exit;
* ``link.ld``: flash at 0x00000000 (4 MB), RAM at 0x20000000 (64 kB; the AN386 map; the
  sizes are read from the sections, not from these regions);
* ``main_size.c``: the stage alone, fed from volatile inputs (so nothing is optimised
  away), its window state a static (in .bss: counted);
* ``main_bench.c``: one real window from flash between two marker functions, printing
  the class, P(healthy), the features' bits and the stack high-water mark by semihosting.
"""

from __future__ import annotations

import numpy as np

STARTUP = r"""#include <stdint.h>
extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);
#define STACK_PAINT 0xC5C5C5C5u

void swg_semihost(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
}

__attribute__((noreturn)) void swg_exit(void)
{
    swg_semihost(0x18u, (const void *)0x20026u);  /* SYS_EXIT, ADP_Stopped_ApplicationExit */
    for (;;) {
    }
}

/* Bytes of stack used so far: the deepest word that lost its paint. */
uint32_t swg_stack_used(void)
{
    uint32_t *p = &_ebss;
    while (p < &_estack && *p == STACK_PAINT) {
        p++;
    }
    return (uint32_t)((uint8_t *)&_estack - (uint8_t *)p);
}

__attribute__((naked, noreturn)) void Reset_Handler(void)
{
    __asm volatile(
        "ldr r0, =_sidata\n ldr r1, =_sdata\n ldr r2, =_edata\n"
        "1: cmp r1, r2\n bcs 2f\n ldr r3, [r0], #4\n str r3, [r1], #4\n b 1b\n"
        "2: ldr r1, =_sbss\n ldr r2, =_ebss\n movs r3, #0\n"
        "3: cmp r1, r2\n bcs 4f\n str r3, [r1], #4\n b 3b\n"
        "4: ldr r2, =0xC5C5C5C5\n mov r3, sp\n sub r3, r3, #64\n"
        "5: cmp r1, r3\n bcs 6f\n str r2, [r1], #4\n b 5b\n"
        "6: ldr r0, =0xE000ED88\n ldr r1, [r0]\n orr r1, r1, #0xF00000\n str r1, [r0]\n"
        "dsb\n isb\n bl main\n bl swg_exit\n");
}

void Default_Handler(void)
{
    swg_exit();
}

__attribute__((section(".isr_vector"), used)) static const void *const vectors[16] = {
    &_estack, Reset_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, 0, 0, 0, 0, Default_Handler, Default_Handler, 0,
    Default_Handler, Default_Handler,
};
"""

LINK = r"""MEMORY
{
  FLASH (rx)  : ORIGIN = 0x00000000, LENGTH = 4096K
  RAM   (rwx) : ORIGIN = 0x20000000, LENGTH = 64K
}
_estack = ORIGIN(RAM) + LENGTH(RAM);
ENTRY(Reset_Handler)
SECTIONS
{
  .isr_vector : { KEEP(*(.isr_vector)) } > FLASH
  .text : { *(.text*) *(.rodata*) . = ALIGN(4); } > FLASH
  .ARM.extab : { *(.ARM.extab*) } > FLASH
  .ARM.exidx : { *(.ARM.exidx*) } > FLASH
  _sidata = LOADADDR(.data);
  .data : { _sdata = .; *(.data*) . = ALIGN(4); _edata = .; } > RAM AT > FLASH
  .bss (NOLOAD) : { _sbss = .; *(.bss*) *(COMMON) . = ALIGN(4); _ebss = .; } > RAM
}
"""

MAIN_SIZE = r"""#include "swg_monitor.h"
static swg_state_t st;  /* the window state (no window buffer: samples are streamed) */
volatile float in_x[SWG_N_BRIDGES], in_phi, in_eff;
volatile int32_t in_op, out_cls;
volatile float out_p;

int main(void)
{
    float x[SWG_N_BRIDGES], p;
    int32_t t, c;
    swg_begin(&st);
    for (t = 0; t < SWG_N_T; t++) {
        for (c = 0; c < SWG_N_BRIDGES; c++) {
            x[c] = in_x[c];
        }
        swg_push(&st, x, in_phi);
    }
    out_cls = swg_end(&st, in_op, in_eff, 0, &p);
    out_p = p;
    return 0;
}
"""

MAIN_EMPTY = r"""int main(void)
{
    return 0;
}
"""

MAIN_BENCH = r"""#include <stdint.h>
#include "swg_monitor.h"
#include "window.h"
void swg_semihost(uint32_t op, const void *arg);
uint32_t swg_stack_used(void);
static swg_state_t st;

__attribute__((noinline)) void swg_mark_begin(void) { __asm volatile("nop"); }
__attribute__((noinline)) void swg_mark_end(void) { __asm volatile("nop"); }

static char *hex(char *p, uint32_t v)
{
    int i;
    for (i = 7; i >= 0; i--) {
        *p++ = "0123456789abcdef"[(v >> (4 * i)) & 15u];
    }
    return p;
}

static char *word(char *p, const char *s)
{
    while (*s) {
        *p++ = *s++;
    }
    return p;
}

int main(void)
{
    static char line[64 + 9 * (SWG_N_FEATURES + 4)];
    float f[SWG_N_FEATURES], p_h = 0.0f;
    int32_t t, c, cls;
    char *q = line;
    swg_mark_begin();
    swg_begin(&st);
    for (t = 0; t < SWG_N_T; t++) {
        swg_push(&st, WIN_X[t], WIN_PHI[t]);  /* the sample as an ADC would leave it */
    }
    cls = swg_end(&st, WIN_OP, WIN_EFF, f, &p_h);
    swg_mark_end();
    q = word(q, "class ");
    q = hex(q, (uint32_t)cls);
    q = word(q, " stack ");
    q = hex(q, swg_stack_used());
    q = word(q, " p ");
    q = hex(q, *(uint32_t *)&p_h);
    q = word(q, " f");
    for (c = 0; c < SWG_N_FEATURES; c++) {
        *q++ = ' ';
        q = hex(q, *(uint32_t *)&f[c]);
    }
    *q++ = '\n';
    *q = 0;
    swg_semihost(0x04u, line);  /* SYS_WRITE0 */
    return 0;
}
"""


def window_header(x: np.ndarray, phi: np.ndarray, op: int, efficiency: float) -> str:
    """``window.h``: one window as flash constants, sample by sample: x (5, n_t) [mV/V] as
    WIN_X[n_t][5], phi (n_t,) [rad]."""
    from swgmon.export.cgen import c_float

    def arr(v):
        return ",\n".join(", ".join(c_float(a) for a in v[i:i + 8]) for i in range(0, len(v), 8))

    rows = ",\n".join("{" + arr(r) + "}" for r in np.asarray(x, np.float32).T)
    ph = arr(np.asarray(phi, np.float32))
    return (f"static const float WIN_X[{x.shape[1]}][5] = {{\n{rows}\n}};\n"
            f"static const float WIN_PHI[{len(phi)}] = {{\n{ph}\n}};\n"
            f"#define WIN_OP {int(op)}\n#define WIN_EFF {c_float(efficiency)}\n")
