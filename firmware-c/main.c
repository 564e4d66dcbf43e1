/*
 * hairsim from C on a Cortex-M4F (QEMU mps2-an386), no heap, no stdio, no math library. First
 * the example (example.c: strands from polylines, the rod's preset, a head sphere, a grab,
 * the grab's force every 100 steps and the state hash), then what CI compares with the host:
 * the scene `firmware` built through the general functions of hairsim.h in a static buffer,
 * stepped 1,000 times, and its state hash (the same as `hairsim run firmware`), with the stack
 * high-water marks of initialisation, of building the scene and of a step, measured by
 * painting the stack.
 */
#include <stddef.h>
#include <stdint.h>

#include "example.h"
#include "firmware_scene.h"
#include "hairsim.h"
#include "semihosting.h"

/* The world: a static buffer, zeroed by start-up (so not yet a world: hairsim_init makes it). */
static HAIRSIM_WORLD_STORAGE(storage);

/* --- Stack high-water marks: paint the free stack, run, find the lowest word changed. --- */

extern uint32_t __stack_limit[];
#define PAINT 0x5AC0FFEEu

static inline uintptr_t stack_pointer(void) {
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

/* Paints everything below its own frame: nothing else uses the stack meanwhile (no
   interrupt is enabled), and a Cortex-M has no red zone below the stack pointer. */
__attribute__((noinline)) static void stack_paint(void) {
    volatile uint32_t *end = (volatile uint32_t *)stack_pointer();
    for (volatile uint32_t *p = __stack_limit; p < end; p++) {
        *p = PAINT;
    }
}

/* Bytes of stack used below `top` since the last paint. */
static uint32_t stack_used(uintptr_t top) {
    const volatile uint32_t *p = __stack_limit;
    while ((uintptr_t)p < top && *p == PAINT) {
        p++;
    }
    return (uint32_t)(top - (uintptr_t)p);
}

static void print(const char *text) {
    line l = {0};
    line_str(&l, text);
    line_print(&l);
}

static int fail(const char *what, hairsim_error e) {
    line l = {0};
    line_str(&l, "error: ");
    line_str(&l, what);
    line_str(&l, ": ");
    line_str(&l, hairsim_error_message(e));
    line_print(&l);
    return 1;
}

int main(void) {
    hairsim_world *world = (hairsim_world *)storage;
    line l = {0};

    hairsim_capacity cap;
    hairsim_error e = hairsim_get_capacity(&cap);
    if (e != HAIRSIM_ERROR_OK || cap.strands != HAIRSIM_STRANDS || cap.nodes != HAIRSIM_NODES ||
        cap.world_size > sizeof storage || cap.world_align > HAIRSIM_WORLD_ALIGN) {
        line_str(&l, "error: the library and hairsim.h differ: capacities ");
        line_u32(&l, cap.strands);
        line_str(&l, "x");
        line_u32(&l, cap.nodes);
        line_str(&l, ", a world of ");
        line_u32(&l, (uint32_t)cap.world_size);
        line_str(&l, " bytes; the header's ");
        line_u32(&l, HAIRSIM_STRANDS);
        line_str(&l, "x");
        line_u32(&l, HAIRSIM_NODES);
        line_str(&l, ", ");
        line_u32(&l, HAIRSIM_WORLD_SIZE);
        line_str(&l, " bytes (run ffi/generate-header.sh)");
        line_print(&l);
        return 1;
    }
    uint64_t hash = 0;
    e = hairsim_state_hash(world, &hash);
    if (e != HAIRSIM_ERROR_NOT_INITIALISED) {
        return fail("a zeroed buffer must not pass for a world", e);
    }

    /* The example, in its own world. */
    static HAIRSIM_WORLD_STORAGE(example_storage);
    hairsim_world *example = (hairsim_world *)example_storage;
    e = hairsim_init(example, sizeof example_storage);
    if (e == HAIRSIM_ERROR_OK) {
        e = example_run(example, print);
    }
    if (e != HAIRSIM_ERROR_OK) {
        return fail("the example", e);
    }

    const uintptr_t top = stack_pointer();
    stack_paint();
    e = hairsim_init(world, sizeof storage);
    const uint32_t init_stack = stack_used(top);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("hairsim_init", e);
    }

    stack_paint();
    e = firmware_scene_build(world);
    const uint32_t build_stack = stack_used(top);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("building the scene", e);
    }

    stack_paint();
    uint32_t rolled_back = 0;
    e = firmware_scene_run(world, &rolled_back);
    const uint32_t step_stack = stack_used(top);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("a step", e);
    }

    firmware_scene_summary summary;
    e = firmware_scene_summarise(world, &summary);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("reading the world", e);
    }

    /* The line CI compares with the host's hash. */
    line_str(&l, "scene firmware steps ");
    line_u32(&l, (uint32_t)summary.steps);
    line_str(&l, " strands ");
    line_u32(&l, summary.strands);
    line_str(&l, summary.all_finite ? " finite true" : " finite false");
    line_str(&l, " grabs held ");
    line_u32(&l, summary.grabs_held);
    line_str(&l, " rolled back ");
    line_u32(&l, rolled_back);
    line_str(&l, " state_hash ");
    line_hex64(&l, summary.state_hash);
    line_print(&l);

    line_str(&l, "stack high-water mark, bytes: hairsim_init ");
    line_u32(&l, init_stack);
    line_str(&l, ", scene build ");
    line_u32(&l, build_stack);
    line_str(&l, ", step ");
    line_u32(&l, step_stack);
    line_str(&l, " (of ");
    line_u32(&l, (uint32_t)(top - (uintptr_t)__stack_limit));
    line_str(&l, " free)");
    line_print(&l);

    line_str(&l, "world buffer, bytes: ");
    line_u32(&l, (uint32_t)cap.world_size);
    line_str(&l, " used of HAIRSIM_WORLD_SIZE ");
    line_u32(&l, HAIRSIM_WORLD_SIZE);
    line_str(&l, ", aligned to ");
    line_u32(&l, (uint32_t)cap.world_align);
    line_print(&l);

    if (__stack_limit[0] != PAINT) {
        semihosting_write0("error: the stack overflowed its 32 KiB\n");
        return 1;
    }
    return summary.all_finite ? 0 : 1;
}
