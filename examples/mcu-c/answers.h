/* The answers to a ray set folded into one FNV-1a hash, exactly as mcu-check's
 * `fold_answers` (examples/mcu/check) folds the Rust queries' answers on the host: per ray,
 * the closest hit's triangle, t, b1 and b2 bits (or 0xFFFFFFFF for a miss), then the any-hit
 * answer (1 or 0). A ray whose any-hit answer disagrees with the closest hit, or that a query
 * refused (status not OK; nothing folded), counts as a leak. Shared by the firmware
 * (main.c) and the host test (ffi/tests/host.c), so both print what `mcu-host` prints. */
#ifndef HALFRAY_ANSWERS_H
#define HALFRAY_ANSWERS_H

#include "halfray.h"

typedef struct Answers {
    uint64_t hash;
    uint32_t queries; /* closest and any hit count one each */
    uint32_t hits;    /* closest hits found */
    uint32_t leaks;   /* refused rays, and any hit disagreeing with closest hit */
} Answers;

static inline Answers answers_new(void) {
    Answers a = {0xcbf29ce484222325ull, 0, 0, 0};
    return a;
}

/* FNV-1a over the little-endian bytes of `w`. */
static inline void answers_word(Answers *a, uint32_t w) {
    for (int k = 0; k < 4; k++) {
        a->hash = (a->hash ^ ((w >> (8 * k)) & 0xffu)) * 0x100000001b3ull;
    }
}

static inline uint32_t answers_bits(float f) {
    uint32_t u;
    __builtin_memcpy(&u, &f, sizeof u);
    return u;
}

/* Closest and any hit of `ray` on `bvh` with the traversal stack `stack` (`entries`
 * entries), folded into `a`. */
static inline void answers_ray(Answers *a, const HalfrayBvh *bvh, const HalfrayRay *ray,
                               HalfrayStackEntry *stack, size_t entries) {
    HalfrayHit hit;
    bool any;
    if (halfray_closest_hit(bvh, ray, stack, entries, &hit) != HALFRAY_STATUS_OK ||
        halfray_any_hit(bvh, ray, stack, entries, &any) != HALFRAY_STATUS_OK) {
        a->leaks++;
        return;
    }
    a->queries += 2;
    bool closest = hit.primitive != HALFRAY_NO_HIT;
    if (closest) {
        a->hits++;
        answers_word(a, hit.primitive);
        answers_word(a, answers_bits(hit.t));
        answers_word(a, answers_bits(hit.b1));
        answers_word(a, answers_bits(hit.b2));
    } else {
        answers_word(a, 0xffffffffu);
    }
    answers_word(a, any ? 1u : 0u);
    a->leaks += any != closest;
}

#endif
