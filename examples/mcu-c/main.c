/* The C firmware of issue 40: a baked BVH (`halfray bake --format bin`) and a ray set, both
 * linked into flash, answered through halfray-ffi's C ABI on a Cortex-M4F (QEMU mps2-an386).
 *
 * Loads the BVH with `halfray_load` (checked as untrusted input; the load scratch on the
 * stack), then makes a closest-hit and an any-hit query per ray on a traversal stack of
 * QUERY_STACK entries and folds the answers into one hash (answers.h). Prints by semihosting
 *
 *   mcu-c: mps2-an386 QUERIES queries hash HEX hits N leaks N stack BYTES traversal BYTES
 *
 * where everything before `stack` must equal what `mcu-host` computes with halfray-core on the
 * host for the same baked scene and rays (scripts/test-mcu.sh compares them), `stack` is the
 * deepest stack the queries used below the point where they are called, measured by painting
 * the stack before them and scanning it after, and `traversal` the traversal stack's bytes.
 * Exits QEMU with 0, or 1 when the load fails, a query is refused or a ray leaks.
 *
 * BAKED_PATH and RAYS_PATH (compile-time strings) name the two files; the rays are
 * `HalfrayRay` records (32 bytes each, little-endian). */
#include <stdint.h>

#include "answers.h"
#include "halfray.h"
#include "startup.h"

#ifndef BAKED_PATH
#error "BAKED_PATH: the baked BVH to link (halfray bake --format bin)"
#endif
#ifndef RAYS_PATH
#error "RAYS_PATH: the rays to answer (HalfrayRay records)"
#endif

/* The baked BVH, HALFRAY_BAKED_ALIGN-aligned, and the rays, in flash. */
__asm__(".section .rodata.baked,\"a\"\n"
        ".balign 32\n"
        "baked: .incbin \"" BAKED_PATH "\"\n"
        "baked_end:\n"
        ".section .rodata.rays,\"a\"\n"
        ".balign 4\n"
        "rays: .incbin \"" RAYS_PATH "\"\n"
        "rays_end:\n"
        ".text\n");
extern const uint8_t baked[], baked_end[];
extern const HalfrayRay rays[], rays_end[];

/* Traversal stack entries given to the queries: as the Rust query image (mcu-check's
 * QUERY_STACK), more than the baked torus needs (`halfray_stack_entries`, which the host test
 * and mcu-host check). Not called here: its tree walk would cost the image 0.2 KiB of its
 * 8 KiB budget; a query that needed more would return HALFRAY_STATUS_STACK_TOO_SMALL, which
 * counts as a leak and fails the run. */
#define QUERY_STACK 24
/* Load scratch words: one bit per triangle, for up to 8 192 triangles. */
#define SCRATCH_WORDS 256
/* Bytes painted below the stack pointer before the queries: more than they may use. */
#define PAINT_BYTES 8192
#define PAINT 0xDEADBEEFu

static inline uintptr_t stack_pointer(void) {
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

/* The lowest stack pointer at which a query was called. */
static uintptr_t call_sp = UINTPTR_MAX;

/* Every ray's queries, out of line so that their whole stack lies below the painting's start. */
__attribute__((noinline)) static Answers queries(const HalfrayBvh *bvh) {
    HalfrayStackEntry stack[QUERY_STACK];
    Answers a = answers_new();
    for (const HalfrayRay *r = rays; r < rays_end; r++) {
        uintptr_t sp = stack_pointer();
        call_sp = sp < call_sp ? sp : call_sp;
        answers_ray(&a, bvh, r, stack, QUERY_STACK);
    }
    return a;
}

/* `queries` with the PAINT_BYTES below the stack pointer painted; `*lowest` is the lowest
 * address whose word no longer holds the paint. */
__attribute__((noinline)) static Answers painted_queries(const HalfrayBvh *bvh, uintptr_t *lowest) {
    uintptr_t top = stack_pointer() & ~(uintptr_t)3, bottom = top - PAINT_BYTES;
    for (uintptr_t p = bottom; p < top; p += 4) {
        *(volatile uint32_t *)p = PAINT;
    }
    Answers a = queries(bvh);
    *lowest = top;
    for (uintptr_t p = bottom; p < top; p += 4) {
        if (*(volatile uint32_t *)p != PAINT) {
            *lowest = p;
            break;
        }
    }
    return a;
}

/* Appends `s` at `*at`. */
static void text(char **at, const char *s) {
    while (*s) {
        *(*at)++ = *s++;
    }
}

/* Appends `v` in decimal. */
static void decimal(char **at, uint32_t v) {
    char buf[10];
    int n = 0;
    do {
        buf[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (n) {
        *(*at)++ = buf[--n];
    }
}

/* Appends `v` as 16 hex digits. */
static void hex(char **at, uint64_t v) {
    for (int k = 60; k >= 0; k -= 4) {
        *(*at)++ = "0123456789abcdef"[(v >> k) & 15];
    }
}

int main(void) {
    static HalfrayBvh bvh;
    uint32_t scratch[SCRATCH_WORDS];
    if (halfray_load(baked, (size_t)(baked_end - baked), scratch, SCRATCH_WORDS, &bvh) !=
        HALFRAY_STATUS_OK) {
        put("mcu-c: the baked BVH did not load\n");
        return 1;
    }
    uintptr_t lowest;
    Answers a = painted_queries(&bvh, &lowest);
    static char line[160];
    char *at = line;
    text(&at, "mcu-c: mps2-an386 ");
    decimal(&at, a.queries);
    text(&at, " queries hash ");
    hex(&at, a.hash);
    text(&at, " hits ");
    decimal(&at, a.hits);
    text(&at, " leaks ");
    decimal(&at, a.leaks);
    text(&at, " stack ");
    decimal(&at, (uint32_t)(call_sp - lowest));
    text(&at, " traversal ");
    decimal(&at, (uint32_t)(QUERY_STACK * sizeof(HalfrayStackEntry)));
    text(&at, "\n");
    *at = 0;
    put(line);
    return a.leaks == 0 ? 0 : 1;
}
