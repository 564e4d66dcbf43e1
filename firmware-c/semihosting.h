/*
 * Output through semihosting (QEMU's -semihosting-config), with a formatter of its own: no
 * stdio, whose printf allocates in newlib.
 */
#ifndef FIRMWARE_C_SEMIHOSTING_H
#define FIRMWARE_C_SEMIHOSTING_H

#include <stddef.h>
#include <stdint.h>

/** SYS_WRITE0: writes a NUL-terminated string to the host's console. */
void semihosting_write0(const char *text);

/** SYS_EXIT: stops QEMU with exit status 0 if `success`, else 1. */
void semihosting_exit(int success) __attribute__((noreturn));

/** A line being built in a fixed buffer: appends are cut at its end, never past it. */
typedef struct line {
    char text[160];
    size_t len;
} line;

void line_str(line *l, const char *s);
void line_u32(line *l, uint32_t v);
/** `0x` and 16 hex digits. */
void line_hex64(line *l, uint64_t v);
/** Writes the line and a newline, then empties it. */
void line_print(line *l);

#endif /* FIRMWARE_C_SEMIHOSTING_H */
