/*
 * The C ABI from C, on the host: builds the scene `firmware` through the general functions,
 * steps it 1,000 times and prints its state hash (the same as `hairsim run firmware --json`;
 * given as the first argument, it is compared), then calls every function with every kind of
 * argument it must refuse and checks the code. Re-entry is provoked by a timer signal whose
 * handler calls into the world the main program is stepping.
 *
 * Also runs the C example (firmware-c/example.c). Built and run by .ci/ffi:
 *   cc -std=c11 -O2 -ffp-contract=off -Iffi/include -Iffi/tests -Ifirmware-c ffi/tests/host.c \
 *      ffi/tests/firmware_scene.c firmware-c/example.c ffi/target/release/libhairsim_ffi.a \
 *      -o host && ./host 0x...
 */
#define _POSIX_C_SOURCE 200809L

#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <time.h>

#include "example.h"
#include "firmware_scene.h"
#include "hairsim.h"

static HAIRSIM_WORLD_STORAGE(scene_storage);
static HAIRSIM_WORLD_STORAGE(refusal_storage);
static HAIRSIM_WORLD_STORAGE(busy_storage);
static HAIRSIM_WORLD_STORAGE(example_storage);

static unsigned passed, failed;

static const char *name_of(hairsim_error code) {
    static const char *const names[] = {
        "OK", "NULL_POINTER", "MISALIGNED", "BUFFER_TOO_SMALL", "NOT_INITIALISED", "BUSY",
        "NOT_FINITE", "OUT_OF_RANGE", "UNSUPPORTED_EFFECT", "TOO_FEW_NODES", "TOO_MANY_NODES",
        "DEGENERATE_SEGMENT", "FOLDED_SEGMENT", "INVALID_MATERIAL", "STRANDS_FULL",
        "COLLIDERS_FULL", "GRABS_FULL", "INVALID_COLLIDER", "INVALID_GRAB", "OVERLAP",
        "VERSION_MISMATCH", "STRANDS_MISMATCH", "NODES_MISMATCH", "EFFECT_OFF",
        "LONG_SEGMENT", "CORRUPT",
    };
    return code >= 0 && (size_t)code < sizeof names / sizeof names[0] ? names[code] : "?";
}

/* Checks that `call` returns `expected`. */
#define EXPECT(expected, call) expect((expected), (call), #call, __LINE__)

static void expect(hairsim_error expected, hairsim_error got, const char *call, int line) {
    if (got == expected) {
        passed++;
        printf("ok   %-18s %s\n", name_of(got), call);
    } else {
        failed++;
        printf("FAIL line %d: %s returned %s (%s), expected %s\n", line, call, name_of(got),
               hairsim_error_message(got), name_of(expected));
    }
}

/* Checks that the world's last refusal names `function`, `argument`, `field` and `index`. */
static void check(int ok, const char *what);

static void refusal(hairsim_world *world, const char *function, const char *argument,
                    const char *field, uint32_t index) {
    hairsim_refusal r;
    int ok = hairsim_last_refusal(world, &r) == HAIRSIM_ERROR_OK &&
             strcmp(r.function, function) == 0 && strcmp(r.argument, argument) == 0 &&
             strcmp(r.field, field) == 0 && r.index == index;
    if (!ok) {
        printf("     refusal: %s %s.%s [%u]\n", r.function, r.argument, r.field,
               (unsigned)r.index);
    }
    char what[160];
    snprintf(what, sizeof what, "the refusal names %s %s.%s [%u]", function, argument, field,
             (unsigned)index);
    check(ok, what);
}

static void check(int ok, const char *what) {
    if (ok) {
        passed++;
        printf("ok   %s\n", what);
    } else {
        failed++;
        printf("FAIL %s\n", what);
    }
}

/* The scene, 1,000 steps: returns 0 and the hash, or 1. */
static int run_scene(uint64_t *hash) {
    hairsim_world *world = (hairsim_world *)scene_storage;
    hairsim_error e = hairsim_init(world, sizeof scene_storage);
    if (e == HAIRSIM_ERROR_OK) {
        e = firmware_scene_build(world);
    }
    uint32_t rolled_back = 0;
    if (e == HAIRSIM_ERROR_OK) {
        e = firmware_scene_run(world, &rolled_back);
    }
    firmware_scene_summary summary;
    if (e == HAIRSIM_ERROR_OK) {
        e = firmware_scene_summarise(world, &summary);
    }
    if (e != HAIRSIM_ERROR_OK) {
        printf("error: the firmware scene: %s\n", hairsim_error_message(e));
        return 1;
    }
    *hash = summary.state_hash;
    printf("scene firmware steps %llu strands %u finite %s grabs held %u rolled back %u "
           "state_hash 0x%016llx\n",
           (unsigned long long)summary.steps, (unsigned)summary.strands,
           summary.all_finite ? "true" : "false", (unsigned)summary.grabs_held,
           (unsigned)rolled_back, (unsigned long long)summary.state_hash);
    return !summary.all_finite;
}

/* Every refused argument, with its code. */
static void refusals(void) {
    unsigned char *bytes = refusal_storage;
    hairsim_world *world = (hairsim_world *)refusal_storage;
    hairsim_capacity cap;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_get_capacity(&cap));
    check(cap.strands == HAIRSIM_STRANDS && cap.nodes == HAIRSIM_NODES,
          "the library's capacities are the header's");
    check(cap.world_size <= HAIRSIM_WORLD_SIZE && cap.world_align <= HAIRSIM_WORLD_ALIGN,
          "the header's world buffer is large and aligned enough");

    /* The header's version and capacities: another minor version (while the major one is 0),
       major version, strand or node capacity than the library's is refused. */
    check(hairsim_version() == HAIRSIM_VERSION, "the library's version is the header's");
    const uint32_t other_minor = HAIRSIM_VERSION ^ (1u << 8);
    const uint32_t other_major = HAIRSIM_VERSION + (1u << 16);
    const uint32_t other_patch = HAIRSIM_VERSION ^ 1u;
    EXPECT(HAIRSIM_ERROR_VERSION_MISMATCH,
           hairsim_init_versioned(world, sizeof refusal_storage, other_minor, HAIRSIM_STRANDS,
                                  HAIRSIM_NODES));
    EXPECT(HAIRSIM_ERROR_VERSION_MISMATCH,
           hairsim_init_versioned(world, sizeof refusal_storage, other_major, HAIRSIM_STRANDS,
                                  HAIRSIM_NODES));
    EXPECT(HAIRSIM_ERROR_STRANDS_MISMATCH,
           hairsim_init_versioned(world, sizeof refusal_storage, HAIRSIM_VERSION,
                                  HAIRSIM_STRANDS + 1, HAIRSIM_NODES));
    EXPECT(HAIRSIM_ERROR_NODES_MISMATCH,
           hairsim_init_versioned(world, sizeof refusal_storage, HAIRSIM_VERSION,
                                  HAIRSIM_STRANDS, HAIRSIM_NODES * 2));
    EXPECT(HAIRSIM_ERROR_NOT_INITIALISED, hairsim_release_grab(world, 0));
    EXPECT(HAIRSIM_ERROR_OK,
           hairsim_init_versioned(world, sizeof refusal_storage, other_patch, HAIRSIM_STRANDS,
                                  HAIRSIM_NODES));
    memset(bytes, 0, HAIRSIM_WORLD_SIZE);

    /* The world buffer: NULL, misaligned, short, uninitialised. */
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_init(NULL, HAIRSIM_WORLD_SIZE));
    EXPECT(HAIRSIM_ERROR_MISALIGNED,
           hairsim_init((hairsim_world *)(bytes + 4), HAIRSIM_WORLD_SIZE - 8));
    EXPECT(HAIRSIM_ERROR_BUFFER_TOO_SMALL, hairsim_init(world, cap.world_size - 1));
    EXPECT(HAIRSIM_ERROR_BUFFER_TOO_SMALL, hairsim_init(world, 0));
    uint64_t hash = 0;
    hairsim_params params;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_params_default(&params));
    EXPECT(HAIRSIM_ERROR_NOT_INITIALISED, hairsim_configure(world, &params));
    EXPECT(HAIRSIM_ERROR_NOT_INITIALISED, hairsim_state_hash(world, &hash));
    hairsim_step_input input = {0};
    input.head.rotation.w = 1.0f;
    EXPECT(HAIRSIM_ERROR_NOT_INITIALISED, hairsim_step(world, &input, NULL));
    EXPECT(HAIRSIM_ERROR_NOT_INITIALISED, hairsim_release_grab(world, 0));
    memset(bytes, 0x5a, HAIRSIM_WORLD_SIZE); /* garbage is no world either */
    EXPECT(HAIRSIM_ERROR_NOT_INITIALISED, hairsim_state_hash(world, &hash));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_init(world, sizeof refusal_storage));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_state_hash(world, &hash));

    /* Parameters: NULL, misaligned, NaN, out of range, unknown values, unsupported effect. */
    hairsim_params p = params;
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_configure(NULL, &p));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_configure(world, NULL));
    EXPECT(HAIRSIM_ERROR_MISALIGNED,
           hairsim_configure((hairsim_world *)(bytes + 1), &p));
    static hairsim_params params_copy[2];
    EXPECT(HAIRSIM_ERROR_MISALIGNED,
           hairsim_configure(world, (const hairsim_params *)((const char *)params_copy + 2)));
    EXPECT(HAIRSIM_ERROR_OVERLAP,
           hairsim_configure(world, (const hairsim_params *)(const void *)(bytes + 64)));
    p.dt = 0.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_configure(world, &p));
    refusal(world, "hairsim_configure", "params", "dt", UINT32_MAX);
    p.dt = 1.0f;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_configure(world, &p));
    p = params;
    p.solver = 42;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_configure(world, &p));
    p = params;
    p.mode = 0xffffffffu;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_configure(world, &p));
    p = params;
    p.effects = 1u << 31;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_configure(world, &p));
    p = params;
    p.rod_projection_iterations = 1u << 20;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_configure(world, &p));
    p = params;
    p.solver = HAIRSIM_SOLVER_DFTL;
    p.effects |= HAIRSIM_EFFECT_GRABS;
    EXPECT(HAIRSIM_ERROR_UNSUPPORTED_EFFECT, hairsim_configure(world, &p));

    /* The default is the rod's preset; a collider or a grab while its effect is off (the
       presets have neither) is refused. */
    hairsim_params preset;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_params_preset(HAIRSIM_SOLVER_ROD, &preset));
    check(memcmp(&preset, &params, sizeof preset) == 0, "the default is the rod's preset");
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_params_preset(2, &preset));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_configure(world, &params));
    hairsim_collider ball = {.shape = HAIRSIM_SHAPE_SPHERE, .attached_to_head = 1,
                             .radius = 0.05f};
    EXPECT(HAIRSIM_ERROR_EFFECT_OFF, hairsim_add_collider(world, &ball, NULL));
    hairsim_grab held = {.strand = 0, .node = 2, .force_limit = 1.0f};
    EXPECT(HAIRSIM_ERROR_EFFECT_OFF, hairsim_add_grab(world, &held, NULL));
    p = params;
    p.effects = HAIRSIM_EFFECT_GRAVITY | HAIRSIM_EFFECT_INEXTENSIBILITY |
                HAIRSIM_EFFECT_COLLISIONS | HAIRSIM_EFFECT_GRABS;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_configure(world, &p));

    /* Strands: NULL, too few and too many points, NaN, degenerate, folded, bad material,
       then until the world is full. */
    hairsim_material hair;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_material_human_hair(&hair));
    hairsim_vec3 line[HAIRSIM_NODES + 1];
    for (size_t i = 0; i <= HAIRSIM_NODES; i++) {
        line[i] = (hairsim_vec3){0.01f * (float)i, 0.0f, 0.0f};
    }
    uint32_t index = 0;
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_add_strand(world, NULL, 5, &hair, &index));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_add_strand(world, line, 5, NULL, &index));
    EXPECT(HAIRSIM_ERROR_TOO_FEW_NODES, hairsim_add_strand(world, line, 2, &hair, &index));
    EXPECT(HAIRSIM_ERROR_TOO_MANY_NODES,
           hairsim_add_strand(world, line, HAIRSIM_NODES + 1, &hair, &index));
    EXPECT(HAIRSIM_ERROR_TOO_MANY_NODES, hairsim_add_strand(world, line, SIZE_MAX, &hair, &index));
    hairsim_vec3 bad[5];
    memcpy(bad, line, sizeof bad);
    bad[3].y = 1.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_add_strand(world, bad, 5, &hair, &index));
    memcpy(bad, line, sizeof bad);
    bad[3] = bad[2];
    EXPECT(HAIRSIM_ERROR_DEGENERATE_SEGMENT, hairsim_add_strand(world, bad, 5, &hair, &index));
    refusal(world, "hairsim_add_strand", "points", "", 2);
    bad[3].x = 1.0e30f;
    EXPECT(HAIRSIM_ERROR_LONG_SEGMENT, hairsim_add_strand(world, bad, 5, &hair, &index));
    refusal(world, "hairsim_add_strand", "points", "", 2);
    memcpy(bad, line, sizeof bad);
    bad[3] = bad[1];
    EXPECT(HAIRSIM_ERROR_FOLDED_SEGMENT, hairsim_add_strand(world, bad, 5, &hair, &index));
    refusal(world, "hairsim_add_strand", "points", "", 2);
    hairsim_material soft = hair;
    soft.radius = 1.0f;
    EXPECT(HAIRSIM_ERROR_INVALID_MATERIAL, hairsim_add_strand(world, line, 5, &soft, &index));
    refusal(world, "hairsim_add_strand", "material", "radius", UINT32_MAX);
    soft.density = 0.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_add_strand(world, line, 5, &soft, &index));
    EXPECT(HAIRSIM_ERROR_MISALIGNED,
           hairsim_add_strand(world, line, 5, &hair, (uint32_t *)(void *)((char *)&hash + 1)));
    EXPECT(HAIRSIM_ERROR_OVERLAP,
           hairsim_add_strand(world, line, 5, &hair, (uint32_t *)(void *)(bytes + 64)));
    for (uint32_t s = 0; s < HAIRSIM_STRANDS; s++) {
        EXPECT(HAIRSIM_ERROR_OK, hairsim_add_strand(world, line, HAIRSIM_NODES, &hair, &index));
    }
    check(index == HAIRSIM_STRANDS - 1, "strand indices count up");
    EXPECT(HAIRSIM_ERROR_STRANDS_FULL, hairsim_add_strand(world, line, 5, &hair, &index));

    /* Colliders. */
    /* Clear of the strands (rooted at the origin): it changes nothing the test looks at. */
    hairsim_collider sphere = {.shape = HAIRSIM_SHAPE_SPHERE, .attached_to_head = 1,
                               .a = {0.0f, -1.0f, 0.0f}, .radius = 0.05f};
    hairsim_collider c = sphere;
    c.shape = 3;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_add_collider(world, &c, NULL));
    c = sphere;
    c.attached_to_head = 2;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_add_collider(world, &c, NULL));
    c = sphere;
    c.radius = 0.0f;
    EXPECT(HAIRSIM_ERROR_INVALID_COLLIDER, hairsim_add_collider(world, &c, NULL));
    c = (hairsim_collider){.shape = HAIRSIM_SHAPE_PLANE, .b = {0.0f, 2.0f, 0.0f}};
    EXPECT(HAIRSIM_ERROR_INVALID_COLLIDER, hairsim_add_collider(world, &c, NULL));
    c = sphere;
    c.a.x = -1.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_add_collider(world, &c, NULL));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_add_collider(world, NULL, NULL));
    for (int i = 0; i < HAIRSIM_MAX_COLLIDERS; i++) {
        EXPECT(HAIRSIM_ERROR_OK, hairsim_add_collider(world, &sphere, NULL));
    }
    EXPECT(HAIRSIM_ERROR_COLLIDERS_FULL, hairsim_add_collider(world, &sphere, NULL));

    /* Grabs. */
    hairsim_grab grab = {.strand = 0, .node = 5, .target = line[5], .force_limit = 1.0f};
    hairsim_grab g = grab;
    g.node = 1;
    EXPECT(HAIRSIM_ERROR_INVALID_GRAB, hairsim_add_grab(world, &g, NULL));
    g.node = HAIRSIM_NODES;
    EXPECT(HAIRSIM_ERROR_INVALID_GRAB, hairsim_add_grab(world, &g, NULL));
    g = grab;
    g.strand = HAIRSIM_STRANDS;
    EXPECT(HAIRSIM_ERROR_INVALID_GRAB, hairsim_add_grab(world, &g, NULL));
    g = grab;
    g.force_limit = -1.0f;
    EXPECT(HAIRSIM_ERROR_INVALID_GRAB, hairsim_add_grab(world, &g, NULL));
    g.force_limit = 0.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_add_grab(world, &g, NULL));
    /* A coupling outside its ranges names its field. */
    g = grab;
    g.stiffness = 1e6f;
    EXPECT(HAIRSIM_ERROR_INVALID_GRAB, hairsim_add_grab(world, &g, NULL));
    refusal(world, "hairsim_add_grab", "grab", "stiffness", UINT32_MAX);
    g.stiffness = 20.0f;
    g.damping = -1.0f;
    EXPECT(HAIRSIM_ERROR_INVALID_GRAB, hairsim_add_grab(world, &g, NULL));
    refusal(world, "hairsim_add_grab", "grab", "damping", UINT32_MAX);
    for (int i = 0; i < HAIRSIM_MAX_GRABS; i++) {
        EXPECT(HAIRSIM_ERROR_OK, hairsim_add_grab(world, &grab, &index));
    }
    EXPECT(HAIRSIM_ERROR_GRABS_FULL, hairsim_add_grab(world, &grab, NULL));
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_release_grab(world, HAIRSIM_MAX_GRABS));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_release_grab(world, HAIRSIM_MAX_GRABS - 1));

    /* Steps: a refused step changes nothing. */
    uint64_t before = 0, after = 0;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_state_hash(world, &before));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_step(world, NULL, NULL));
    hairsim_step_input in = {0};
    in.head.rotation.w = 0.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_step(world, &in, NULL));
    in.head.rotation.w = 0.5f;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_step(world, &in, NULL));
    in.head.rotation.w = 1.0f;
    hairsim_vec3 targets[HAIRSIM_MAX_GRABS + 1] = {{0}};
    in.grab_targets = targets;
    in.grab_target_count = HAIRSIM_MAX_GRABS + 1;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_step(world, &in, NULL));
    in.grab_target_count = 1;
    in.grab_targets = NULL;
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_step(world, &in, NULL));
    in.grab_targets = targets;
    targets[0].z = 0.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_step(world, &in, NULL));
    targets[0] = line[5];
    static hairsim_vec3 accelerations[HAIRSIM_STRANDS * HAIRSIM_NODES + 1];
    in.accelerations = accelerations;
    in.acceleration_count = HAIRSIM_STRANDS * HAIRSIM_NODES + 1;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_step(world, &in, NULL));
    in.acceleration_count = 3;
    accelerations[2].y = 1.0f / 0.0f;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_step(world, &in, NULL));
    accelerations[2].y = 0.0f;
    in.accelerations = (const hairsim_vec3 *)(const void *)(bytes + 256);
    EXPECT(HAIRSIM_ERROR_OVERLAP, hairsim_step(world, &in, NULL));
    in.accelerations = accelerations;
    hairsim_step_report report;
    EXPECT(HAIRSIM_ERROR_MISALIGNED,
           hairsim_step(world, &in, (hairsim_step_report *)(void *)((char *)&report + 1)));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_state_hash(world, &after));
    check(before == after, "refused steps changed nothing");
    EXPECT(HAIRSIM_ERROR_OK, hairsim_step(world, &in, &report));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_state_hash(world, &after));
    check(before != after, "a step changes the state");

    /* Positions: short buffer (and the count it needs), NULL, unknown strand, overlap. */
    hairsim_vec3 out[HAIRSIM_NODES];
    size_t count = 0;
    EXPECT(HAIRSIM_ERROR_BUFFER_TOO_SMALL, hairsim_strand_positions(world, 0, out, 3, &count));
    check(count == HAIRSIM_NODES, "a short buffer is told the count it needs");
    EXPECT(HAIRSIM_ERROR_BUFFER_TOO_SMALL, hairsim_strand_positions(world, 0, NULL, 0, &count));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_strand_positions(world, 0, NULL, 3, &count));
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE,
           hairsim_strand_positions(world, HAIRSIM_STRANDS, out, HAIRSIM_NODES, &count));
    EXPECT(HAIRSIM_ERROR_OVERLAP,
           hairsim_strand_positions(world, 0, (hairsim_vec3 *)(void *)(bytes + 8), 1000, &count));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_strand_positions(world, 0, out, HAIRSIM_NODES, NULL));
    check(out[0].x == line[0].x && out[1].x == line[1].x, "the roots stay where they were put");
    EXPECT(HAIRSIM_ERROR_MISALIGNED,
           hairsim_state_hash(world, (uint64_t *)(void *)((char *)out + 4)));
    EXPECT(HAIRSIM_ERROR_OVERLAP, hairsim_state_hash(world, (uint64_t *)(void *)bytes));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_get_info(world, NULL));

    /* Helpers. */
    hairsim_shake shake = {.axis = {0.0f, 1.0f, 0.0f}, .amplitude = 0.5f, .frequency = 3.0f};
    hairsim_pose pose;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_shake_pose(&shake, 0.1f, &pose));
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_shake_pose(&shake, 1.0f / 0.0f, &pose));
    shake.axis.y = 2.0f;
    EXPECT(HAIRSIM_ERROR_OUT_OF_RANGE, hairsim_shake_pose(&shake, 0.1f, &pose));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_shake_pose(NULL, 0.1f, &pose));
    hairsim_circle circle = {.start = {3.0e38f, 0.0f, 0.0f}, .radius = 3.0e38f,
                             .frequency = 2.0f};
    hairsim_vec3 target;
    EXPECT(HAIRSIM_ERROR_NOT_FINITE, hairsim_circle_target(&circle, 0.25f, &target));
    EXPECT(HAIRSIM_ERROR_NULL_POINTER, hairsim_circle_target(&circle, 0.25f, NULL));

    /* Every code has a message, an unknown one too. */
    int messages = 1;
    for (int code = -3; code < 40; code++) {
        const char *m = hairsim_error_message(code);
        messages &= m != NULL && m[0] != '\0';
    }
    check(messages, "every code has a message");
    check(strcmp(hairsim_error_message(12345), "unknown error code") == 0,
          "an unknown code says so");
}

/* Re-entry: a timer signal calls into the world the main program is stepping. */
static volatile sig_atomic_t busy_seen, ok_seen, other_seen;

static void on_timer(int signal) {
    (void)signal;
    uint64_t hash;
    hairsim_error e = hairsim_state_hash((hairsim_world *)busy_storage, &hash);
    if (e == HAIRSIM_ERROR_BUSY) {
        busy_seen++;
    } else if (e == HAIRSIM_ERROR_OK) {
        ok_seen++;
    } else {
        other_seen++;
    }
}

static void reentry(void) {
    hairsim_world *world = (hairsim_world *)busy_storage;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_init(world, sizeof busy_storage));
    EXPECT(HAIRSIM_ERROR_OK, firmware_scene_build(world));
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = on_timer;
    sigemptyset(&action.sa_mask);
    sigaction(SIGALRM, &action, NULL);
    struct itimerval every = {{0, 200}, {0, 200}};
    setitimer(ITIMER_REAL, &every, NULL);
    hairsim_error e = HAIRSIM_ERROR_OK;
    time_t start = time(NULL);
    for (uint32_t k = 0; e == HAIRSIM_ERROR_OK && busy_seen < 3 && time(NULL) - start < 20; k++) {
        e = firmware_scene_step(world, k % firmware_scene_steps, NULL);
    }
    struct itimerval off = {{0, 0}, {0, 0}};
    setitimer(ITIMER_REAL, &off, NULL);
    EXPECT(HAIRSIM_ERROR_OK, e);
    printf("     re-entry: %d calls refused busy, %d ran between steps\n", (int)busy_seen,
           (int)ok_seen);
    check(busy_seen >= 3 && other_seen == 0, "a call from a signal handler during a step is BUSY");
    uint64_t hash;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_state_hash(world, &hash));
}

static void no_hook(const char *file, size_t file_len, uint32_t line) {
    (void)file;
    (void)file_len;
    (void)line;
}

/* Integrity: a built world passes the check and recovers; every 7th byte of it changed in turn,
   a step either runs or refuses the world as corrupt; the panic hook is set and returned. */
static void integrity(void) {
    hairsim_world *world = (hairsim_world *)busy_storage;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_init(world, sizeof busy_storage));
    EXPECT(HAIRSIM_ERROR_OK, firmware_scene_build(world));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_check(world));
    EXPECT(HAIRSIM_ERROR_OK, hairsim_recover(world));
    static unsigned char copy[HAIRSIM_WORLD_SIZE];
    memcpy(copy, busy_storage, sizeof copy);
    unsigned corrupt = 0, other = 0;
    hairsim_capacity cap;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_get_capacity(&cap));
    for (size_t offset = 0; offset < cap.world_size; offset += 7) {
        memcpy(busy_storage, copy, sizeof copy);
        busy_storage[offset] ^= 0xA5u;
        hairsim_error e = firmware_scene_step(world, 0, NULL);
        corrupt += e == HAIRSIM_ERROR_CORRUPT;
        other += e != HAIRSIM_ERROR_OK && e != HAIRSIM_ERROR_CORRUPT &&
                 e != HAIRSIM_ERROR_NOT_INITIALISED && e != HAIRSIM_ERROR_BUSY;
    }
    printf("     corruption: every 7th byte of the world changed, %u steps refused as corrupt\n",
           corrupt);
    check(corrupt > 0 && other == 0, "a corrupted world steps or is refused as corrupt");
    memcpy(busy_storage, copy, sizeof copy);
    EXPECT(HAIRSIM_ERROR_OK, hairsim_check(world));
    check(hairsim_set_panic_hook(no_hook) == NULL, "no panic hook at first");
    check(hairsim_set_panic_hook(NULL) == no_hook, "the panic hook set is returned");
}

static void print_line(const char *text) { printf("%s\n", text); }

/* firmware-c/example.c, as the C firmware runs it: .ci/ffi compares the lines both print. */
static void example(void) {
    hairsim_world *world = (hairsim_world *)example_storage;
    EXPECT(HAIRSIM_ERROR_OK, hairsim_init(world, sizeof example_storage));
    EXPECT(HAIRSIM_ERROR_OK, example_run(world, print_line));
}

int main(int argc, char **argv) {
    uint64_t hash = 0;
    example();
    int scene_failed = run_scene(&hash);
    check(!scene_failed, "the scene ran, every node finite");
    if (argc > 1) {
        char *end = NULL;
        unsigned long long expected = strtoull(argv[1], &end, 16);
        int same = end != argv[1] && *end == '\0' && expected == hash;
        if (!same) {
            printf("host hash %s, C hash 0x%016llx\n", argv[1], (unsigned long long)hash);
        }
        check(same, "the C hash is the host's (hairsim run firmware)");
    }
    refusals();
    reentry();
    integrity();
    printf("host C test: %u passed, %u failed\n", passed, failed);
    return failed != 0;
}
