#include "semihosting.h"

enum { SYS_WRITE0 = 0x04, SYS_EXIT = 0x18 };
/* SYS_EXIT reasons: ADP_Stopped_ApplicationExit and ADP_Stopped_RunTimeErrorUnknown. */
enum { EXIT_OK = 0x20026, EXIT_ERROR = 0x20023 };

static uint32_t semihost(uint32_t op, uintptr_t arg) {
    register uint32_t r0 __asm__("r0") = op;
    register uintptr_t r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void semihosting_write0(const char *text) { semihost(SYS_WRITE0, (uintptr_t)text); }

void semihosting_exit(int success) {
    semihost(SYS_EXIT, success ? EXIT_OK : EXIT_ERROR);
    for (;;) {
    }
}

static void line_char(line *l, char c) {
    if (l->len + 1 < sizeof l->text) {
        l->text[l->len++] = c;
    }
}

void line_str(line *l, const char *s) {
    while (*s) {
        line_char(l, *s++);
    }
}

void line_u32(line *l, uint32_t v) {
    char digits[10];
    int n = 0;
    do {
        digits[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (n) {
        line_char(l, digits[--n]);
    }
}

void line_hex64(line *l, uint64_t v) {
    line_str(l, "0x");
    for (int shift = 60; shift >= 0; shift -= 4) {
        line_char(l, "0123456789abcdef"[(v >> shift) & 0xf]);
    }
}

void line_print(line *l) {
    line_char(l, '\n');
    l->text[l->len] = '\0';
    semihosting_write0(l->text);
    l->len = 0;
}
