/*
 * The scene `firmware`, built and stepped through the general functions of hairsim.h: the
 * same f32 operations in the same order as the Rust scene, so the same state hash. No math
 * library: the head's pose and the grab targets come from hairsim_shake_pose and
 * hairsim_circle_target.
 */
#include "firmware_scene.h"

#include <stddef.h>

#include "firmware_scene_data.h"

const uint32_t firmware_scene_steps = FIRMWARE_STEPS;

hairsim_error firmware_scene_build(hairsim_world *world) {
    hairsim_error e = hairsim_configure(world, &FIRMWARE_PARAMS);
    for (size_t c = 0; e == HAIRSIM_ERROR_OK && c < FIRMWARE_COLLIDERS; c++) {
        e = hairsim_add_collider(world, &FIRMWARE_COLLIDER[c], NULL);
    }
    for (size_t s = 0; e == HAIRSIM_ERROR_OK && s < FIRMWARE_STRANDS; s++) {
        e = hairsim_add_strand(world, FIRMWARE_POINT[s], FIRMWARE_POINT_COUNT[s],
                               &FIRMWARE_MATERIAL, NULL);
    }
    for (size_t g = 0; e == HAIRSIM_ERROR_OK && g < FIRMWARE_GRABS; g++) {
        e = hairsim_add_grab(world, &FIRMWARE_GRAB[g], NULL);
    }
    return e;
}

hairsim_error firmware_scene_step(hairsim_world *world, uint32_t k, hairsim_step_report *report) {
    /* As the Rust scene: t = (k + 1) as f32 * dt, one IEEE multiplication. */
    const float t = (float)(k + 1u) * FIRMWARE_PARAMS.dt;
    hairsim_vec3 targets[FIRMWARE_GRABS];
    hairsim_step_input input = {0};
    hairsim_error e = hairsim_shake_pose(&FIRMWARE_SHAKE, t, &input.head);
    for (size_t g = 0; e == HAIRSIM_ERROR_OK && g < FIRMWARE_GRABS; g++) {
        e = hairsim_circle_target(&FIRMWARE_GRAB_CIRCLE[g], t, &targets[g]);
    }
    if (e != HAIRSIM_ERROR_OK) {
        return e;
    }
    input.grab_targets = targets;
    input.grab_target_count = FIRMWARE_GRABS;
    return hairsim_step(world, &input, report);
}

hairsim_error firmware_scene_run(hairsim_world *world, uint32_t *rolled_back) {
    hairsim_error e = HAIRSIM_ERROR_OK;
    *rolled_back = 0;
    for (uint32_t k = 0; e == HAIRSIM_ERROR_OK && k < firmware_scene_steps; k++) {
        hairsim_step_report report;
        e = firmware_scene_step(world, k, &report);
        *rolled_back += report.rolled_back;
    }
    return e;
}

/* Finite without a math library: NaN fails x == x, ±∞ gives NaN for x − x. */
static int finite(float x) { return x == x && x - x == 0.0f; }

hairsim_error firmware_scene_summarise(hairsim_world *world, firmware_scene_summary *out) {
    hairsim_world_info info;
    hairsim_error e = hairsim_get_info(world, &info);
    out->all_finite = 1;
    for (uint32_t s = 0; e == HAIRSIM_ERROR_OK && s < info.strands; s++) {
        hairsim_vec3 positions[HAIRSIM_NODES];
        size_t count = 0;
        e = hairsim_strand_positions(world, s, positions, HAIRSIM_NODES, &count);
        for (size_t i = 0; i < count; i++) {
            out->all_finite &=
                finite(positions[i].x) & finite(positions[i].y) & finite(positions[i].z);
        }
    }
    if (e == HAIRSIM_ERROR_OK) {
        e = hairsim_state_hash(world, &out->state_hash);
    }
    if (e != HAIRSIM_ERROR_OK) {
        return e;
    }
    out->steps = info.steps;
    out->strands = info.strands;
    out->grabs_held = 0;
    for (uint32_t g = 0; g < info.grabs; g++) {
        out->grabs_held += info.grab_status[g] == HAIRSIM_GRAB_STATUS_HELD;
    }
    return HAIRSIM_ERROR_OK;
}
