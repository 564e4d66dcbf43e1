/*
 * The scene `firmware` of hairsim_core::scenes (the world `hairsim run firmware` steps),
 * built and stepped through the general functions of hairsim.h only, from the data in
 * firmware_scene_data.h. Shared by the host test (ffi/tests/host.c) and the bare-metal
 * example (firmware-c/).
 */
#ifndef HAIRSIM_FIRMWARE_SCENE_H
#define HAIRSIM_FIRMWARE_SCENE_H

#include <stdint.h>

#include "hairsim.h"

/** Steps the scene runs before its state hash is compared (1000). */
extern const uint32_t firmware_scene_steps;

/** Configures an initialised, empty world and adds the scene's colliders, strands and grabs. */
hairsim_error firmware_scene_build(hairsim_world *world);

/**
 * Step k (0-based) of the scene: at t = (k + 1) dt, the head's pose of the shake and the grab
 * targets on their circles, then one hairsim_step. `report` may be NULL.
 */
hairsim_error firmware_scene_step(hairsim_world *world, uint32_t k, hairsim_step_report *report);

/** Steps 0 … firmware_scene_steps − 1, adding up the strands each step rolled back. */
hairsim_error firmware_scene_run(hairsim_world *world, uint32_t *rolled_back);

/** What both programs print of the world after the run (the line CI compares). */
typedef struct firmware_scene_summary {
    uint64_t steps;
    uint32_t strands;
    /** 1 when every node position is finite. */
    int all_finite;
    uint32_t grabs_held;
    uint64_t state_hash;
} firmware_scene_summary;

/** Reads the summary of `world`. */
hairsim_error firmware_scene_summarise(hairsim_world *world, firmware_scene_summary *out);

#endif /* HAIRSIM_FIRMWARE_SCENE_H */
