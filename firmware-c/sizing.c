/*
 * The sizing table's measurements (ffi/sizing.py builds and runs this for each capacity): the
 * library built for HAIRSIM_STRANDS x HAIRSIM_NODES under QEMU (mps2-an386, Cortex-M4F, run
 * with -icount shift=0 so that SysTick counts instructions: one tick is 40 of them).
 *
 * Every scene starts from the solver's preset with collisions and grabs on, a 5 cm head
 * sphere and one grab (strand 0's middle node, carried over 50 ms onto a 5 mm circle at 2 Hz
 * nearer the root), and fills the world: HAIRSIM_STRANDS strands of HAIRSIM_NODES nodes, 1 cm apart,
 * rooted around the sphere as firmware/src/latency.rs roots them. Calm: the head still, the
 * hair hanging. Violent: the head shaking at 10 rad/s (Kmoch 2009), the hair starting
 * horizontal. Rod scenes also run violent with hair ten times stiffer, which takes the
 * linearly implicit bending step from the first step. Each scene runs in converge and in
 * fixed-cost mode, STEPS steps.
 *
 * Prints, for ffi/sizing.py: the world's size, the stack high-water marks of hairsim_init and
 * of building each scene, and per scene the instruction ticks of every step (minimum, median,
 * maximum), the deepest stack of its steps, and what the steps reported (rolled back, grab
 * held at the end, most contacts). The stack is measured by painting it, as main.c does.
 */
#include <stddef.h>
#include <stdint.h>

#include "hairsim.h"
#include "semihosting.h"

#define STEPS 200u

static HAIRSIM_WORLD_STORAGE(storage);

/* --- SysTick on the core clock, free-running (24 bits, counting down). --- */

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

static void systick_start(void) {
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0;
    SYST_CSR = 5u; /* enable, core clock, no interrupt */
}

static uint32_t systick_now(void) { return SYST_CVR; }

/* --- Stack high-water marks: paint the free stack, run, find the lowest word changed. --- */

extern uint32_t __stack_limit[];
#define PAINT 0x5AC0FFEEu

static inline uintptr_t stack_pointer(void) {
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

__attribute__((noinline)) static void stack_paint(void) {
    volatile uint32_t *end = (volatile uint32_t *)stack_pointer();
    for (volatile uint32_t *p = __stack_limit; p < end; p++) {
        *p = PAINT;
    }
}

static uint32_t stack_used(uintptr_t top) {
    const volatile uint32_t *p = __stack_limit;
    while ((uintptr_t)p < top && *p == PAINT) {
        p++;
    }
    return (uint32_t)(top - (uintptr_t)p);
}

/* --- The scenes. --- */

typedef struct scene {
    const char *name;
    uint32_t solver;
    uint32_t mode;
    int violent;
    /* Young's and shear moduli times this (10: the implicit bending step). */
    float stiffness;
} scene;

static const hairsim_shake ten_rad_per_s = {
    .axis = {0.0f, 1.0f, 0.0f},
    .centre = {0.0f, 0.0f, 0.0f},
    .amplitude = 0.5f,
    /* 10 / (0.5 * 2 pi): a peak angular speed of 10 rad/s, as Shake::TEN_RAD_PER_S. */
    .frequency = 3.18309886f,
};

/* The root direction of strand s round the vertical: the golden angle (2.399963 rad) a
   strand, as latency.rs spreads them; its cosine and sine, so that no C math library is
   needed. */
static void root_direction(uint32_t s, float *x, float *z) {
    const float golden_cos = -0.73736872f, golden_sin = 0.67549046f;
    float c = 1.0f, n = 0.0f;
    for (uint32_t k = 0; k < s; k++) {
        const float next = c * golden_cos - n * golden_sin;
        n = c * golden_sin + n * golden_cos;
        c = next;
    }
    *x = c;
    *z = n;
}

/* Strand s's rest polyline, 1 cm segments from a root on the 5 cm head sphere. Violent: from
   the equator, sticking out horizontally. Calm: draped over the sphere 0.2 mm above it, from
   30 degrees of latitude down to the equator, then hanging (the head's contacts run). The
   drape's arc is taken by 1 cm chords: the cosines and sines of the angle a chord turns are
   constants, so that no C math library is needed. */
static void polyline(uint32_t s, int violent, hairsim_vec3 *points) {
    float dx, dz;
    root_direction(s, &dx, &dz);
    const float radius = 0.0502f;
    /* A 1 cm chord of the drape turns 2 asin(0.005 / 0.0502) rad. */
    const float turn_cos = 0.98015905f, turn_sin = 0.19821263f;
    float up_sin = 0.5f, up_cos = 0.86602540f; /* 30 degrees */
    float y = 0.0f;
    for (uint32_t i = 0; i < HAIRSIM_NODES; i++) {
        float out, height;
        if (violent) {
            out = 0.05f + 0.01f * (float)i;
            height = 0.0f;
        } else if (up_sin > 0.0f) {
            out = radius * up_cos;
            height = radius * up_sin;
            const float next = up_sin * turn_cos - up_cos * turn_sin;
            up_cos = up_cos * turn_cos + up_sin * turn_sin;
            up_sin = next;
            y = height;
        } else {
            out = radius + 0.0001f * (float)i;
            y -= 0.01f;
            height = y;
        }
        points[i].x = dx * out;
        points[i].y = height;
        points[i].z = dz * out;
    }
}

/* The grab holds node HAIRSIM_NODES / 2 of strand 0 on a 5 mm circle at 2 Hz, 1.5 cm nearer
   the root than the node lies: always within the strand's reach. */
static hairsim_circle grab_circle(const hairsim_vec3 *points) {
    const hairsim_vec3 node = points[HAIRSIM_NODES / 2], before = points[HAIRSIM_NODES / 2 - 1];
    /* Back along the last segment (1 cm long), one and a half segments. */
    hairsim_circle c = {.radius = 0.005f, .frequency = 2.0f};
    c.start.x = node.x + 1.5f * (before.x - node.x);
    c.start.y = node.y + 1.5f * (before.y - node.y);
    c.start.z = node.z + 1.5f * (before.z - node.z);
    return c;
}

/* Where the grabbed node is at rest (world frame: the head starts at the identity). */
static hairsim_vec3 grab_node;

static hairsim_error build(hairsim_world *world, const scene *sc, hairsim_circle *circle) {
    hairsim_params params;
    hairsim_error e = hairsim_params_preset(sc->solver, &params);
    if (e != HAIRSIM_ERROR_OK) {
        return e;
    }
    params.mode = sc->mode;
    params.effects |= HAIRSIM_EFFECT_COLLISIONS | HAIRSIM_EFFECT_GRABS;
    e = hairsim_configure(world, &params);
    if (e != HAIRSIM_ERROR_OK) {
        return e;
    }
    const hairsim_collider head = {.shape = HAIRSIM_SHAPE_SPHERE, .attached_to_head = 1,
                                   .radius = 0.05f};
    e = hairsim_add_collider(world, &head, NULL);
    hairsim_material hair;
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_material_human_hair(&hair);
    }
    hair.youngs_modulus *= sc->stiffness;
    hair.shear_modulus *= sc->stiffness;
    static hairsim_vec3 points[HAIRSIM_NODES];
    for (uint32_t s = 0; s < HAIRSIM_STRANDS && e == HAIRSIM_ERROR_OK; s++) {
        polyline(s, sc->violent, points);
        e = hairsim_add_strand(world, points, HAIRSIM_NODES, &hair, NULL);
        if (s == 0) {
            *circle = grab_circle(points);
            grab_node = points[HAIRSIM_NODES / 2];
        }
    }
    if (e == HAIRSIM_ERROR_OK) {
        const hairsim_grab grab = {.strand = 0, .node = HAIRSIM_NODES / 2,
                                   .target = grab_node, .force_limit = 10.0f};
        e = hairsim_add_grab(world, &grab, NULL);
    }
    return e;
}

/* Ticks of each step, sorted afterwards. */
static uint32_t ticks[STEPS];

static void sort(uint32_t *t, uint32_t n) {
    for (uint32_t i = 1; i < n; i++) {
        const uint32_t v = t[i];
        uint32_t j = i;
        for (; j > 0 && t[j - 1] > v; j--) {
            t[j] = t[j - 1];
        }
        t[j] = v;
    }
}

static int fail(const char *what, hairsim_error e) {
    line l = {0};
    line_str(&l, "sizing error: ");
    line_str(&l, what);
    line_str(&l, ": ");
    line_str(&l, hairsim_error_message(e));
    line_print(&l);
    return 1;
}

/* Builds and runs one scene; prints its lines. */
static int run(hairsim_world *world, const scene *sc, uintptr_t top) {
    hairsim_error e = hairsim_init(world, sizeof storage);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("hairsim_init", e);
    }
    hairsim_circle circle;
    stack_paint();
    e = build(world, sc, &circle);
    const uint32_t build_stack = stack_used(top);
    line l = {0};
    if (e == HAIRSIM_ERROR_OUT_OF_RANGE) {
        /* A library built without this solver (cargo feature off) refuses it. */
        line_str(&l, "sizing scene ");
        line_str(&l, sc->name);
        line_str(&l, sc->mode == HAIRSIM_MODE_FIXED_COST ? " fixed-cost" : " converge");
        line_str(&l, " not built");
        line_print(&l);
        return 0;
    }
    if (e != HAIRSIM_ERROR_OK) {
        return fail(sc->name, e);
    }
    uint32_t rolled_back = 0, contacts = 0, flags = 0;
    float stretch = 0.0f;
    hairsim_step_input input = {.head = {.rotation = {.w = 1.0f}}};
    hairsim_vec3 target;
    hairsim_step_report report;
    float dt = 0.001f;
    stack_paint();
    for (uint32_t k = 0; k < STEPS && e == HAIRSIM_ERROR_OK; k++) {
        const float t = (float)(k + 1) * dt;
        if (sc->violent) {
            e = hairsim_shake_pose(&ten_rad_per_s, t, &input.head);
        }
        if (e == HAIRSIM_ERROR_OK) {
            e = hairsim_circle_target(&circle, t, &target);
            /* From the node's rest position to the circle over the first 50 ms. */
            const float ramp = t < 0.05f ? t / 0.05f : 1.0f;
            target.x = grab_node.x + ramp * (target.x - grab_node.x);
            target.y = grab_node.y + ramp * (target.y - grab_node.y);
            target.z = grab_node.z + ramp * (target.z - grab_node.z);
            input.grab_targets = &target;
            input.grab_target_count = 1;
        }
        const uint32_t before = systick_now();
        if (e == HAIRSIM_ERROR_OK) {
            e = hairsim_step(world, &input, &report);
        }
        const uint32_t after = systick_now();
        ticks[k] = (before - after) & 0x00FFFFFFu;
        rolled_back += report.rolled_back;
        contacts = report.contacts > contacts ? report.contacts : contacts;
        flags |= report.flags;
        stretch = report.max_stretch > stretch ? report.max_stretch : stretch;
        stretch = report.max_contact_stretch > stretch ? report.max_contact_stretch : stretch;
    }
    const uint32_t step_stack = stack_used(top);
    if (e != HAIRSIM_ERROR_OK) {
        return fail(sc->name, e);
    }
    hairsim_world_info info;
    e = hairsim_get_info(world, &info);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("hairsim_get_info", e);
    }
    sort(ticks, STEPS);
    line_str(&l, "sizing scene ");
    line_str(&l, sc->name);
    line_str(&l, sc->mode == HAIRSIM_MODE_FIXED_COST ? " fixed-cost" : " converge");
    line_str(&l, " ticks ");
    line_u32(&l, ticks[0]);
    line_str(&l, " ");
    line_u32(&l, ticks[STEPS / 2]);
    line_str(&l, " ");
    line_u32(&l, ticks[STEPS - 1]);
    line_str(&l, " stack build ");
    line_u32(&l, build_stack);
    line_str(&l, " step ");
    line_u32(&l, step_stack);
    line_str(&l, " rolled_back ");
    line_u32(&l, rolled_back);
    line_str(&l, " grab ");
    line_str(&l, info.grab_status[0] == HAIRSIM_GRAB_STATUS_HELD ? "held" : "slipped");
    line_str(&l, " contacts ");
    line_u32(&l, contacts);
    line_str(&l, " flags ");
    line_u32(&l, flags);
    line_str(&l, " stretch_ppm ");
    line_u32(&l, (uint32_t)(stretch * 1e6f));
    line_print(&l);
    return 0;
}

static const scene scenes[] = {
    {"rod calm", HAIRSIM_SOLVER_ROD, HAIRSIM_MODE_CONVERGE, 0, 1.0f},
    {"rod violent", HAIRSIM_SOLVER_ROD, HAIRSIM_MODE_CONVERGE, 1, 1.0f},
    {"rod stiff", HAIRSIM_SOLVER_ROD, HAIRSIM_MODE_CONVERGE, 1, 10.0f},
    {"dftl calm", HAIRSIM_SOLVER_DFTL, HAIRSIM_MODE_CONVERGE, 0, 1.0f},
    {"dftl violent", HAIRSIM_SOLVER_DFTL, HAIRSIM_MODE_CONVERGE, 1, 1.0f},
};

int main(void) {
    hairsim_world *world = (hairsim_world *)storage;
    systick_start();
    hairsim_capacity cap;
    hairsim_error e = hairsim_get_capacity(&cap);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("hairsim_get_capacity", e);
    }
    const uintptr_t top = stack_pointer();
    stack_paint();
    e = hairsim_init(world, sizeof storage);
    const uint32_t init_stack = stack_used(top);
    if (e != HAIRSIM_ERROR_OK) {
        return fail("hairsim_init", e);
    }
    line l = {0};
    line_str(&l, "sizing strands ");
    line_u32(&l, HAIRSIM_STRANDS);
    line_str(&l, " nodes ");
    line_u32(&l, HAIRSIM_NODES);
    line_str(&l, " world ");
    line_u32(&l, (uint32_t)cap.world_size);
    line_str(&l, " header ");
    line_u32(&l, HAIRSIM_WORLD_SIZE);
    line_str(&l, " stack init ");
    line_u32(&l, init_stack);
    line_print(&l);
    for (uint32_t m = 0; m < 2; m++) {
        for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++) {
            scene sc = scenes[i];
            sc.mode = m == 0 ? HAIRSIM_MODE_CONVERGE : HAIRSIM_MODE_FIXED_COST;
            if (run(world, &sc, top) != 0) {
                return 1;
            }
        }
    }
    if (__stack_limit[0] != PAINT) {
        semihosting_write0("sizing error: the stack overflowed\n");
        return 1;
    }
    semihosting_write0("sizing done\n");
    return 0;
}
