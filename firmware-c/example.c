/*
 * hairsim's C example (example.h says what it does). Units are SI: metres, seconds,
 * kilograms, newtons. The world's y axis points up: the presets' gravity is (0, -9.81, 0).
 * Strands and head-attached colliders are given in the head's frame; each step's head pose
 * (a rotation about the head's origin, then a translation) places that frame in the world,
 * and grab targets are given in the world. At the identity pose the two frames coincide.
 */
#include "example.h"

#include <stddef.h>
#include <stdint.h>

#if HAIRSIM_STRANDS < 4 || HAIRSIM_NODES < 16
#error "the example needs a library of at least 4 strands of 16 nodes"
#endif

enum { STRANDS = 4, NODES = 16, STEPS = 1000, REPORT_EVERY = 100 };

/* A 5 cm head sphere around the head's origin; hair of 15 nodes 1 cm apart sideways. */
#define HEAD_RADIUS 0.05f
#define SEGMENT 0.01f

/* Strand s's rest polyline, root first: from a root on the head sphere 30 degrees above its
   equator, on one of its four sides, out 1 cm a node and drooping (i^2 / 2 mm at node i), a
   curve whose tip lies nearer the root than the hair's length. Gravity lays it on the head. */
static void strand_polyline(int s, hairsim_vec3 points[NODES]) {
    static const float side[4][2] = {{1.0f, 0.0f}, {0.0f, 1.0f}, {-1.0f, 0.0f}, {0.0f, -1.0f}};
    const float cos30 = 0.8660254f, sin30 = 0.5f;
    for (int i = 0; i < NODES; i++) {
        const float out = HEAD_RADIUS * cos30 + SEGMENT * (float)i;
        points[i].x = side[s][0] * out;
        points[i].y = HEAD_RADIUS * sin30 - 0.0005f * (float)(i * i);
        points[i].z = side[s][1] * out;
    }
}

/* The head turns about the vertical, 0.3 rad either way, once a second. */
static const hairsim_shake head_shake = {
    .axis = {0.0f, 1.0f, 0.0f}, .centre = {0.0f, 0.0f, 0.0f}, .amplitude = 0.3f,
    .frequency = 1.0f};

/* The grab holds strand 0's tip where it starts, then draws a 2 cm circle a second. */
static hairsim_circle grab_path;

static hairsim_error build(hairsim_world *world) {
    /* The rod's preset (gravity, drag, bending, twist, inextensibility), plus the two effects
       the scene's collider and grab need: adding them with their effects off is refused. */
    hairsim_params params;
    hairsim_error e = hairsim_params_preset(HAIRSIM_SOLVER_ROD, &params);
    if (e != HAIRSIM_ERROR_OK) {
        return e;
    }
    params.effects |= HAIRSIM_EFFECT_COLLISIONS | HAIRSIM_EFFECT_GRABS;
    if ((e = hairsim_configure(world, &params)) != HAIRSIM_ERROR_OK) {
        return e;
    }
    const hairsim_collider head = {.shape = HAIRSIM_SHAPE_SPHERE, .attached_to_head = 1,
                                   .a = {0.0f, 0.0f, 0.0f}, .radius = HEAD_RADIUS};
    if ((e = hairsim_add_collider(world, &head, NULL)) != HAIRSIM_ERROR_OK) {
        return e;
    }
    hairsim_material hair;
    if ((e = hairsim_material_human_hair(&hair)) != HAIRSIM_ERROR_OK) {
        return e;
    }
    hairsim_vec3 points[NODES];
    for (int s = 0; s < STRANDS; s++) {
        strand_polyline(s, points);
        if ((e = hairsim_add_strand(world, points, NODES, &hair, NULL)) != HAIRSIM_ERROR_OK) {
            return e;
        }
    }
    /* Strand 0's tip (node NODES - 1), held at its rest position to start with. */
    strand_polyline(0, points);
    grab_path = (hairsim_circle){.start = points[NODES - 1], .radius = 0.02f, .frequency = 1.0f};
    const hairsim_grab grab = {.strand = 0, .node = NODES - 1, .target = points[NODES - 1],
                               .force_limit = 1.0f};
    return hairsim_add_grab(world, &grab, NULL);
}

/* --- A line of text without stdio. --- */

typedef struct text {
    char buffer[128];
    size_t len;
} text;

static void put(text *t, const char *s) {
    while (*s != '\0' && t->len + 1 < sizeof t->buffer) {
        t->buffer[t->len++] = *s++;
    }
    t->buffer[t->len] = '\0';
}

static void put_u64(text *t, uint64_t v, int min_digits) {
    char digits[21];
    int n = 0;
    do {
        digits[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v != 0 || n < min_digits);
    char out[22];
    for (int i = 0; i < n; i++) {
        out[i] = digits[n - 1 - i];
    }
    out[n] = '\0';
    put(t, out);
}

/* `v` newtons as micronewtons with three decimals, e.g. " -12.345". */
static void put_micro(text *t, float v) {
    const float nano = v * 1.0e9f;
    const int negative = nano < 0.0f;
    const uint64_t n = (uint64_t)((negative ? -nano : nano) + 0.5f);
    put(t, negative ? " -" : " ");
    put_u64(t, n / 1000, 1);
    put(t, ".");
    put_u64(t, n % 1000, 3);
}

static void put_hex64(text *t, uint64_t v) {
    char out[19] = "0x";
    for (int i = 0; i < 16; i++) {
        out[2 + i] = "0123456789abcdef"[(v >> (60 - 4 * i)) & 0xf];
    }
    out[18] = '\0';
    put(t, out);
}

/* --- Stepping. --- */

hairsim_error example_run(hairsim_world *world, example_print print) {
    hairsim_error e = build(world);
    hairsim_params params;
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_params_preset(HAIRSIM_SOLVER_ROD, &params);
    }
    hairsim_step_input input = {0};
    hairsim_vec3 target;
    hairsim_step_report report;
    for (uint32_t k = 0; k < STEPS && e == HAIRSIM_ERROR_OK; k++) {
        /* Each tick: the head's pose and the grab's target at the end of the step. */
        const float t = (float)(k + 1) * params.dt;
        e = hairsim_shake_pose(&head_shake, t, &input.head);
        if (e == HAIRSIM_ERROR_OK) {
            e = hairsim_circle_target(&grab_path, t, &target);
        }
        input.grab_targets = &target;
        input.grab_target_count = 1;
        if (e == HAIRSIM_ERROR_OK) {
            e = hairsim_step(world, &input, &report);
        }
        if (e == HAIRSIM_ERROR_OK && (k + 1) % REPORT_EVERY == 0) {
            /* The force the hair pulls the grab with: what a haptic device renders. */
            text line = {{0}, 0};
            put(&line, "example step ");
            put_u64(&line, k + 1, 1);
            put(&line, " grab force (uN)");
            put_micro(&line, report.grab_forces[0].x);
            put_micro(&line, report.grab_forces[0].y);
            put_micro(&line, report.grab_forces[0].z);
            put(&line, report.flags & HAIRSIM_FLAG_GRAB_SLIPPED ? " slipped" : "");
            put(&line, report.flags & HAIRSIM_FLAG_STRETCHED ? " stretched" : "");
            print(line.buffer);
        }
    }
    uint64_t hash = 0;
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_state_hash(world, &hash);
    }
    if (e == HAIRSIM_ERROR_OK) {
        text line = {{0}, 0};
        put(&line, "example steps ");
        put_u64(&line, STEPS, 1);
        put(&line, " state_hash ");
        put_hex64(&line, hash);
        print(line.buffer);
    }
    return e;
}
