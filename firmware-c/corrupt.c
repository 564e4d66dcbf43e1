/*
 * Stray writes into a world, under QEMU (mps2-an386, Cortex-M4F, -icount shift=0 so that the
 * run is the same every time): 1,000 single-byte corruptions at random offsets of a built
 * world, each followed by three steps. Each must end in one of three ways: the steps run,
 * a call returns an error (HAIRSIM_ERROR_CORRUPT for a byte hairsim_check's first part
 * catches), or the library calls the panic hook. A hard fault or a hang (a trial running
 * past a budget a hundred times a normal one's) is counted, and CI requires none of either.
 * Then the panic hook itself: the library built with its `panic-test` feature panics on
 * purpose, and the hook must be called.
 *
 * Half the trials corrupt a rod world, half a DFTL one (each solver's preset, collisions and
 * grabs, a head sphere, HAIRSIM_STRANDS draped strands, a grab: prescribed on the rod, through
 * a virtual coupling on DFTL),
 * stepped 20 times before the copy that each trial starts from is taken. Prints one line for
 * .ci/ffi: `corruption trials ... stepped ... error ... hook ... hardfault ... hang ...`.
 *
 * A fault or the watchdog returns from its exception into `escape`, which jumps back to the
 * trial loop (setjmp/longjmp): the frames of the call it left are abandoned, and the world
 * is restored from its copy for the next trial.
 */
#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "hairsim.h"
#include "semihosting.h"

#define TRIALS 1000u
#define STEPS 3u
/* SysTick interrupts every 100,000 ticks (4 million instructions under -icount shift=0); a
   trial still running after 50 of them is a hang (three steps take about a million). */
#define WATCHDOG_RELOAD 100000u
#define WATCHDOG_LIMIT 50u

enum outcome { STEPPED = 0, ERROR = 1, HOOK = 2, HARDFAULT = 3, HANG = 4, OUTCOMES = 5 };
static const char *const outcome_names[OUTCOMES] = {"stepped", "error", "hook", "hardfault",
                                                    "hang"};

static HAIRSIM_WORLD_STORAGE(storage);
static unsigned char pristine[2][HAIRSIM_WORLD_SIZE] __attribute__((aligned(8)));
static size_t world_size;

static jmp_buf escape_to;
static volatile uint32_t escaped;
static volatile uint32_t armed, watchdog_ticks;
static volatile uint32_t hook_line;

/* --- Leaving a call that faulted, hung or panicked. --- */

void escape(void) { longjmp(escape_to, 1); }

/* Makes the exception return into `escape` in thread mode: the stacked PC and xPSR (the
   Thumb bit alone) of the frame the exception pushed. */
static void return_to_escape(uint32_t *frame, uint32_t why) {
    escaped = why;
    frame[6] = (uint32_t)(uintptr_t)escape & ~1u;
    frame[7] = 1u << 24;
}

void fault_c(uint32_t *frame) { return_to_escape(frame, HARDFAULT); }

void systick_c(uint32_t *frame) {
    if (armed && ++watchdog_ticks > WATCHDOG_LIMIT) {
        armed = 0;
        return_to_escape(frame, HANG);
    }
}

/* The frame is on the main or the process stack, as EXC_RETURN's bit 2 says. */
__attribute__((naked)) void fault_handler(void) {
    __asm__ volatile("tst lr, #4\n\tite eq\n\tmrseq r0, msp\n\tmrsne r0, psp\n\tb fault_c\n");
}

__attribute__((naked)) void systick_handler(void) {
    __asm__ volatile("tst lr, #4\n\tite eq\n\tmrseq r0, msp\n\tmrsne r0, psp\n\tb systick_c\n");
}

static void hook(const char *file, size_t file_len, uint32_t line) {
    (void)file;
    (void)file_len;
    hook_line = line;
    escaped = HOOK;
    longjmp(escape_to, 1);
}

/* --- The worlds. --- */

static uint32_t random_state = 0x2545F491u;

/* xorshift32: the same trials every run. */
static uint32_t next_random(void) {
    uint32_t x = random_state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return random_state = x;
}

static const hairsim_shake shake = {.axis = {0.0f, 1.0f, 0.0f}, .amplitude = 0.5f,
                                    .frequency = 3.18309886f};

static hairsim_error build(hairsim_world *world, uint32_t solver) {
    hairsim_params params;
    hairsim_error e = hairsim_params_preset(solver, &params);
    params.effects |= HAIRSIM_EFFECT_COLLISIONS | HAIRSIM_EFFECT_GRABS;
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_configure(world, &params);
    }
    const hairsim_collider head = {.shape = HAIRSIM_SHAPE_SPHERE, .attached_to_head = 1,
                                   .radius = 0.05f};
    hairsim_material hair;
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_add_collider(world, &head, NULL);
    }
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_material_human_hair(&hair);
    }
    static const float side[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    hairsim_vec3 points[HAIRSIM_NODES];
    for (uint32_t s = 0; s < HAIRSIM_STRANDS && e == HAIRSIM_ERROR_OK; s++) {
        for (uint32_t i = 0; i < HAIRSIM_NODES; i++) {
            const float out = 0.0433f + 0.01f * (float)i;
            points[i].x = side[s % 4][0] * out + 0.001f * (float)(s / 4);
            points[i].y = 0.025f - 0.0005f * (float)(i * i);
            points[i].z = side[s % 4][1] * out;
        }
        e = hairsim_add_strand(world, points, HAIRSIM_NODES, &hair, NULL);
    }
    if (e == HAIRSIM_ERROR_OK) {
        hairsim_grab grab = {.strand = 0, .node = HAIRSIM_NODES / 2,
                             .target = points[HAIRSIM_NODES / 2], .force_limit = 1.0f};
        if (solver == HAIRSIM_SOLVER_DFTL) {
            /* A device's coupling (docs/haptics.md): a world with a grab of each kind. */
            grab.stiffness = 50.0f;
            grab.damping = 0.01f;
        }
        e = hairsim_add_grab(world, &grab, NULL);
    }
    return e;
}

/* Steps `first` .. `first + count - 1`; the first error. */
static hairsim_error run_steps(hairsim_world *world, uint32_t first, uint32_t count) {
    hairsim_step_input input = {0};
    hairsim_error e = HAIRSIM_ERROR_OK;
    for (uint32_t k = first; k < first + count && e == HAIRSIM_ERROR_OK; k++) {
        e = hairsim_shake_pose(&shake, (float)(k + 1) * 0.001f, &input.head);
        if (e == HAIRSIM_ERROR_OK) {
            e = hairsim_step(world, &input, NULL);
        }
    }
    return e;
}

static int fail(const char *what, hairsim_error e) {
    line l = {0};
    line_str(&l, "corruption error: ");
    line_str(&l, what);
    line_str(&l, ": ");
    line_str(&l, hairsim_error_message(e));
    line_print(&l);
    return 1;
}

/* --- The trials. --- */

static uint32_t counts[OUTCOMES], errors[32], check_refused;

/* One trial: the world `scene` with the byte at `offset` changed by `mask`, three steps. */
static void trial(hairsim_world *world, uint32_t scene, uint32_t offset, uint8_t mask) {
    memcpy(storage, pristine[scene], world_size);
    storage[offset] ^= mask;
    escaped = 0;
    watchdog_ticks = 0;
    if (setjmp(escape_to) != 0) {
        armed = 0;
        counts[escaped]++;
        return;
    }
    armed = 1;
    const hairsim_error e = run_steps(world, 20, STEPS);
    armed = 0;
    if (e != HAIRSIM_ERROR_OK) {
        counts[ERROR]++;
        errors[(uint32_t)e < 32 ? (uint32_t)e : 31]++;
        return;
    }
    counts[STEPPED]++;
    check_refused += hairsim_check(world) == HAIRSIM_ERROR_CORRUPT;
}

static void print_counts(void) {
    line l = {0};
    line_str(&l, "corruption trials ");
    line_u32(&l, TRIALS);
    for (uint32_t k = 0; k < OUTCOMES; k++) {
        line_str(&l, " ");
        line_str(&l, outcome_names[k]);
        line_str(&l, " ");
        line_u32(&l, counts[k]);
    }
    line_print(&l);
    for (uint32_t code = 0; code < 32; code++) {
        if (errors[code] != 0) {
            line_str(&l, "corruption error ");
            line_str(&l, hairsim_error_message((int32_t)code));
            line_str(&l, ": ");
            line_u32(&l, errors[code]);
            line_print(&l);
        }
    }
    line_str(&l, "corruption stepped, then refused by hairsim_check: ");
    line_u32(&l, check_refused);
    line_print(&l);
}

/* The hook itself: a library built with `panic-test` panics when asked. */
void hairsim_test_panic(void);

static int test_hook(void) {
    escaped = 0;
    if (setjmp(escape_to) == 0) {
        hairsim_test_panic();
    }
    line l = {0};
    line_str(&l, escaped == HOOK ? "corruption panic hook called, line "
                                 : "corruption panic hook NOT called, line ");
    line_u32(&l, hook_line);
    line_print(&l);
    return escaped == HOOK ? 0 : 1;
}

int main(void) {
    hairsim_world *world = (hairsim_world *)storage;
    hairsim_capacity cap;
    hairsim_error e = hairsim_get_capacity(&cap);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("capacity", e);
    }
    world_size = cap.world_size;
    const uint32_t solvers[2] = {HAIRSIM_SOLVER_ROD, HAIRSIM_SOLVER_DFTL};
    for (uint32_t scene = 0; scene < 2; scene++) {
        memset(storage, 0, sizeof storage);
        e = hairsim_init(world, sizeof storage);
        if (e == HAIRSIM_ERROR_OK) {
            e = build(world, solvers[scene]);
        }
        if (e == HAIRSIM_ERROR_OK) {
            e = run_steps(world, 0, 20);
        }
        if (e != HAIRSIM_ERROR_OK) {
            return fail("building the worlds", e);
        }
        memcpy(pristine[scene], storage, world_size);
    }
    hairsim_set_panic_hook(hook);
    /* SysTick: reload, current value, then enabled with its interrupt on the core clock. */
    volatile uint32_t *syst = (volatile uint32_t *)0xE000E010u;
    syst[1] = WATCHDOG_RELOAD;
    syst[2] = 0;
    syst[0] = 7u;
    for (uint32_t t = 0; t < TRIALS; t++) {
        const uint32_t offset = next_random() % (uint32_t)world_size;
        const uint8_t mask = (uint8_t)(1u + next_random() % 255u);
        trial(world, t & 1u, offset, mask);
    }
    print_counts();
    return test_hook() | (counts[HARDFAULT] != 0) | (counts[HANG] != 0);
}
