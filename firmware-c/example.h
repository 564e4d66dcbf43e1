/*
 * hairsim's C example, as a firmware engineer would write it from hairsim.h: four strands
 * built from polylines, the rod's preset with collisions and grabs, a head sphere, a grab on a
 * strand's tip, 1,000 steps of a head shaking, the grab's force every 100 steps and the state
 * hash at the end. Portable C (no stdio, no math library): firmware-c/main.c runs it under
 * QEMU, ffi/tests/host.c on the host, and .ci/ffi compares what both print.
 */
#ifndef HAIRSIM_EXAMPLE_H
#define HAIRSIM_EXAMPLE_H

#include "hairsim.h"

/* Prints one line of text (without its newline). */
typedef void (*example_print)(const char *line);

/*
 * Builds the example in `world` (an initialised world of at least 4 strands of 16 nodes),
 * steps it 1,000 times, printing the grab's force every 100 steps and the state hash at the
 * end. Returns the first error.
 */
hairsim_error example_run(hairsim_world *world, example_print print);

#endif /* HAIRSIM_EXAMPLE_H */
