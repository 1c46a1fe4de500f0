/* halfray-ffi on the host, from C, under AddressSanitizer and UndefinedBehaviorSanitizer
 * (scripts/test-ffi.sh builds it with -Wall -Wextra -Werror -fsanitize=address,undefined):
 * every function with good input and with bad input (NULL, short and misaligned buffers,
 * corrupted baked BVHs, invalid rays, small stacks), each result checked against the header's
 * contract; a query's outputs must be untouched when it fails.
 *
 *   host OCTAHEDRON.bin TORUS.bin RAYS.bin 'mcu-c: mps2-an386 ...'
 *
 * The octahedron (scenes/meshes/octahedron.obj, baked) has answers known in closed form; the
 * torus and rays are the C firmware's, and the line this program computes from them must be
 * the one `mcu-host` computed with halfray-core (the last argument). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../examples/mcu-c/answers.h"
#include "halfray.h"

static int failures;

#define CHECK(cond)                                                                     \
    do {                                                                                \
        if (!(cond)) {                                                                  \
            fprintf(stderr, "host.c:%d: check failed: %s\n", __LINE__, #cond);          \
            failures++;                                                                 \
        }                                                                               \
    } while (0)

/* A file in memory, HALFRAY_BAKED_ALIGN-aligned. */
typedef struct Buffer {
    uint8_t *bytes;
    size_t len;
} Buffer;

/* `size` or more bytes, HALFRAY_BAKED_ALIGN-aligned, zeroed. */
static uint8_t *aligned_bytes(size_t size) {
    size = (size / HALFRAY_BAKED_ALIGN + 1) * HALFRAY_BAKED_ALIGN;
    uint8_t *p = aligned_alloc(HALFRAY_BAKED_ALIGN, size);
    if (!p) {
        exit(2);
    }
    return memset(p, 0, size);
}

static Buffer read_file(const char *path) {
    Buffer b = {NULL, 0};
    FILE *f = fopen(path, "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0) {
        fprintf(stderr, "host: cannot read %s\n", path);
        exit(2);
    }
    long n = ftell(f);
    rewind(f);
    b.bytes = aligned_bytes(n < 0 ? 0 : (size_t)n);
    if (n < 0 || fread(b.bytes, 1, (size_t)n, f) != (size_t)n) {
        fprintf(stderr, "host: cannot read %s\n", path);
        exit(2);
    }
    fclose(f);
    b.len = (size_t)n;
    return b;
}

static Buffer copy(Buffer b) {
    Buffer c = {aligned_bytes(b.len), b.len};
    memcpy(c.bytes, b.bytes, b.len);
    return c;
}

static void put_u32(uint8_t *at, uint32_t w) { memcpy(at, &w, 4); }
static uint32_t get_u32(const uint8_t *at) {
    uint32_t w;
    memcpy(&w, at, 4);
    return w;
}

static HalfrayRay ray(float ox, float oy, float oz, float dx, float dy, float dz) {
    HalfrayRay r = {{ox, oy, oz}, {dx, dy, dz}, 0.0f, INFINITY};
    return r;
}

/* `halfray_load` of a copy of `b` after `corrupt(copy)`; returns the status. */
static HalfrayStatus load_corrupted(Buffer b, void (*corrupt)(Buffer)) {
    Buffer c = copy(b);
    corrupt(c);
    uint32_t scratch[4];
    HalfrayBvh bvh;
    HalfrayStatus s = halfray_load(c.bytes, c.len, scratch, 4, &bvh);
    HalfrayStackEntry stack[HALFRAY_MAX_STACK_ENTRIES];
    HalfrayRay r = ray(0.25f, 0.25f, 5.0f, 0.0f, 0.0f, -1.0f);
    HalfrayHit hit;
    /* A refused buffer leaves the handle not loaded. */
    if (s != HALFRAY_STATUS_OK) {
        CHECK(halfray_closest_hit(&bvh, &r, stack, HALFRAY_MAX_STACK_ENTRIES, &hit) ==
              HALFRAY_STATUS_NOT_LOADED);
    }
    free(c.bytes);
    return s;
}

/* The octahedron's layout: 6 vertices, 8 triangles, K nodes (header word 5). */
static uint32_t nodes_of(Buffer b) { return get_u32(b.bytes + 20); }
static size_t positions_at(Buffer b) { return 32 + 32 * (size_t)nodes_of(b); }
static size_t triangles_at(Buffer b) { return positions_at(b) + 12 * 6; }
static size_t indices_at(Buffer b) { return triangles_at(b) + 12 * 8; }

static void bad_magic(Buffer b) { b.bytes[0] ^= 1; }
static void bad_reserved(Buffer b) { b.bytes[28] = 1; }
static void bad_version(Buffer b) { put_u32(b.bytes + 8, 2); }
static void root_child_before(Buffer b) { put_u32(b.bytes + 32 + 24, 0); }
static void root_child_past(Buffer b) { put_u32(b.bytes + 32 + 24, nodes_of(b)); }
static void root_box_nan(Buffer b) {
    float nan = NAN;
    memcpy(b.bytes + 32, &nan, 4);
}
static void root_box_inverted(Buffer b) {
    float big = 10.0f;
    memcpy(b.bytes + 32, &big, 4);
}
static void vertex_index_out_of_range(Buffer b) { put_u32(b.bytes + triangles_at(b), 6); }
static void vertex_nan(Buffer b) {
    float nan = NAN;
    memcpy(b.bytes + positions_at(b), &nan, 4);
}
static void index_repeated(Buffer b) {
    put_u32(b.bytes + indices_at(b) + 4, get_u32(b.bytes + indices_at(b)));
}
static void index_out_of_range(Buffer b) { put_u32(b.bytes + indices_at(b), 8); }

/* A baked buffer of `t` triangles (0,0,0) (1,0,0) (0,1,0) in one leaf whose indices list
 * triangle 32 * `word` + j for each set bit j of `bits`, then the first of them again: the
 * load check marks one scratch bit per listed triangle, so it sets exactly `bits` in scratch
 * word `word`, then fails with BAD_INDEX. */
static Buffer spelling(uint32_t word, uint32_t bits, uint32_t t) {
    const uint32_t v = 3;
    size_t len = 32 + 32 + 12 * v + 16 * (size_t)t;
    Buffer b = {aligned_bytes(len), len};
    memcpy(b.bytes, "halfray\0", 8);
    put_u32(b.bytes + 8, 1);
    put_u32(b.bytes + 12, v);
    put_u32(b.bytes + 16, t);
    put_u32(b.bytes + 20, 1);
    const float one = 1.0f;
    for (int k = 0; k < 3; k++) memcpy(b.bytes + 44 + 4 * k, &one, 4); /* root box [0, 1]^3 */
    put_u32(b.bytes + 60, t);                                          /* a leaf of t triangles */
    memcpy(b.bytes + 64 + 12, &one, 4);                                /* (0,0,0) (1,0,0) (0,1,0) */
    memcpy(b.bytes + 64 + 28, &one, 4);
    size_t tri = 64 + 12 * v, idx = tri + 12 * (size_t)t, at = 0;
    for (uint32_t i = 0; i < t; i++) {
        put_u32(b.bytes + tri + 12 * i + 4, 1);
        put_u32(b.bytes + tri + 12 * i + 8, 2);
    }
    uint32_t first = 0;
    for (uint32_t bit = 0; bit < 32; bit++)
        if (bits >> bit & 1) {
            if (!at) first = 32 * word + bit;
            put_u32(b.bytes + idx + 4 * at++, 32 * word + bit);
        }
    put_u32(b.bytes + idx + 4 * at, first);
    return b;
}

/* A failed load whose scratch shares the handle's memory leaves the handle "not loaded",
 * whatever the scratch's bits: a crafted buffer lists the triangles whose bits spell a loaded
 * handle's first words, the tag 0x48524159 ^ buffer address with the address word 0. The
 * handle used to pass the "loaded" check, and a query answered OK from it. */
static void forged_tag_in_shared_scratch(void) {
    Buffer b = spelling(8, 0x48524159u, 32 * 9);
    _Alignas(HalfrayBvh) uint32_t scratch[64];
    memset(scratch, 0, sizeof scratch);
    HalfrayBvh *h = (HalfrayBvh *)(void *)(scratch + 8);
    CHECK(halfray_load(b.bytes, b.len, scratch, 64, h) == HALFRAY_STATUS_BAD_INDEX);
    HalfrayRay r = ray(0.25f, 0.25f, 5.0f, 0.0f, 0.0f, -1.0f);
    HalfrayStackEntry stack[HALFRAY_MAX_STACK_ENTRIES];
    HalfrayHit hit;
    CHECK(halfray_closest_hit(h, &r, stack, HALFRAY_MAX_STACK_ENTRIES, &hit) ==
          HALFRAY_STATUS_NOT_LOADED);
    free(b.bytes);
}

/* The same with 0x48524159 spelled in the handle's second word (the buffer's address), the
 * tag word 0: 0 is 0x48524159 ^ 0x48524159. The handle held a loaded octahedron and the
 * scratch covers only its first two words, so the rest of that tree stays behind: a failed
 * load used to leave a handle the queries accepted, answering OK from the earlier tree. */
static void forged_address_in_shared_scratch(Buffer oct) {
    const uint32_t per = sizeof(size_t) / 4; /* scratch words per handle word */
    const uint32_t address_word = 8 + per, words = 8 + 2 * per;
    Buffer b = spelling(address_word, 0x48524159u, 32 * words);
    Buffer earlier = copy(oct);
    _Alignas(HalfrayBvh) uint32_t scratch[64];
    memset(scratch, 0, sizeof scratch);
    HalfrayBvh *h = (HalfrayBvh *)(void *)(scratch + 8);
    uint32_t own[1];
    CHECK(halfray_load(earlier.bytes, earlier.len, own, 1, h) == HALFRAY_STATUS_OK);
    CHECK(halfray_load(b.bytes, b.len, scratch, words, h) == HALFRAY_STATUS_BAD_INDEX);
    HalfrayRay r = ray(0.25f, 0.25f, 5.0f, 0.0f, 0.0f, -1.0f);
    HalfrayStackEntry stack[HALFRAY_MAX_STACK_ENTRIES];
    HalfrayHit hit, sentinel;
    memset(&sentinel, 0x5A, sizeof sentinel);
    hit = sentinel;
    size_t entries = 999;
    bool any = true;
    CHECK(halfray_stack_entries(h, &entries) == HALFRAY_STATUS_NOT_LOADED && entries == 999);
    CHECK(halfray_closest_hit(h, &r, stack, HALFRAY_MAX_STACK_ENTRIES, &hit) ==
          HALFRAY_STATUS_NOT_LOADED);
    CHECK(halfray_any_hit(h, &r, stack, HALFRAY_MAX_STACK_ENTRIES, &any) ==
          HALFRAY_STATUS_NOT_LOADED);
    CHECK(memcmp(&hit, &sentinel, sizeof hit) == 0 && any);
    free(earlier.bytes);
    free(b.bytes);
}

/* A baked node as the format lays it out: box, then (first child, 0) for an inner node or
 * (first index, count) for a leaf. */
typedef struct Node {
    float lo[3], hi[3];
    uint32_t start, count;
} Node;

/* `halfray_load` of a buffer of `k` hand-written nodes over `t` triangles, all of them the
 * triangle (0,0,0) (1,0,0) (0,1,0), listed by `indices`. */
static HalfrayStatus load_nodes(uint32_t t, uint32_t k, const Node *nodes, const uint32_t *indices) {
    const uint32_t v = 3;
    size_t len = 32 + 32 * (size_t)k + 12 * v + 16 * (size_t)t;
    uint8_t *b = aligned_bytes(len);
    memcpy(b, "halfray\0", 8);
    put_u32(b + 8, 1);
    put_u32(b + 12, v);
    put_u32(b + 16, t);
    put_u32(b + 20, k);
    memcpy(b + 32, nodes, 32 * (size_t)k);
    size_t pos = 32 + 32 * (size_t)k, tri = pos + 12 * v;
    const float one = 1.0f;
    memcpy(b + pos + 12, &one, 4);
    memcpy(b + pos + 28, &one, 4);
    for (uint32_t i = 0; i < t; i++) {
        put_u32(b + tri + 12 * i + 4, 1);
        put_u32(b + tri + 12 * i + 8, 2);
    }
    memcpy(b + tri + 12 * (size_t)t, indices, 4 * (size_t)t);
    uint32_t scratch[8];
    HalfrayBvh bvh;
    memset(&bvh, 0, sizeof bvh);
    HalfrayStatus status = halfray_load(b, len, scratch, 8, &bvh);
    free(b);
    return status;
}

/* The checks of a baked tree that no corruption of a built one reaches, each on a tree
 * written by hand to fail it alone: its own code. */
#define UNIT_BOX {0, 0, 0}, {1, 1, 1}
static void hand_built_trees_get_their_codes(void) {
    uint32_t indices[66];
    for (uint32_t i = 0; i < 66; i++) indices[i] = i;
    /* Two triangles cannot need five nodes (at most 2t - 1 = 3). */
    Node five[5] = {{UNIT_BOX, 0, 2}, {UNIT_BOX, 0, 1}, {UNIT_BOX, 0, 1}, {UNIT_BOX, 0, 1},
                    {UNIT_BOX, 0, 1}};
    CHECK(load_nodes(2, 5, five, indices) == HALFRAY_STATUS_NODE_COUNT);
    /* Node 0's children are 1 and 2, node 1's are 2 and 3: node 2 has two parents. */
    Node shared[4] = {{UNIT_BOX, 1, 0}, {UNIT_BOX, 2, 0}, {UNIT_BOX, 0, 1}, {UNIT_BOX, 1, 1}};
    CHECK(load_nodes(2, 4, shared, indices) == HALFRAY_STATUS_SHARED_NODE);
    /* A leaf of indices [1, 3) of a list of two runs past it; a leaf of [0, 1) leaves
     * triangle 1 unlisted. */
    Node past[1] = {{UNIT_BOX, 1, 2}};
    CHECK(load_nodes(2, 1, past, indices) == HALFRAY_STATUS_LEAF_RANGE);
    Node half[1] = {{UNIT_BOX, 0, 1}};
    CHECK(load_nodes(2, 1, half, indices) == HALFRAY_STATUS_UNCOVERED);
    /* A chain of 65 inner nodes, each with a leaf and the next inner node as children:
     * deeper than any tree the core builds. */
    static Node chain[131];
    uint32_t leaf = 0;
    for (int i = 0; i < 131; i++) {
        Node n = {UNIT_BOX, 0, 0};
        if (i % 2 == 0 && i < 130) {
            n.start = (uint32_t)i + 1;
        } else {
            n.start = leaf++;
            n.count = 1;
        }
        chain[i] = n;
    }
    CHECK(load_nodes(66, 131, chain, indices) == HALFRAY_STATUS_TOO_DEEP);
    /* And a correct one-leaf tree over both: loaded. */
    Node whole[1] = {{UNIT_BOX, 0, 2}};
    CHECK(load_nodes(2, 1, whole, indices) == HALFRAY_STATUS_OK);
}

static void octahedron(Buffer b) {
    HalfrayBakedInfo info;
    memset(&info, 0xAB, sizeof info);
    HalfrayBakedInfo untouched = info;
    /* halfray_baked_info: good, then NULL, short, misaligned and foreign buffers. */
    CHECK(halfray_baked_info(b.bytes, b.len, &info) == HALFRAY_STATUS_OK);
    CHECK(info.vertices == 6 && info.triangles == 8 && info.scratch_words == 1);
    CHECK(info.nodes == nodes_of(b) && info.nodes >= 3);
    CHECK(info.byte_len == b.len && b.len == 32 + 32 * info.nodes + 12 * 6 + 16 * 8);
    HalfrayBakedInfo again = untouched;
    CHECK(halfray_baked_info(NULL, b.len, &again) == HALFRAY_STATUS_NULL);
    CHECK(halfray_baked_info(b.bytes, b.len, NULL) == HALFRAY_STATUS_NULL);
    CHECK(halfray_baked_info(b.bytes, 31, &again) == HALFRAY_STATUS_SHORT_BUFFER);
    CHECK(halfray_baked_info(b.bytes, b.len - 1, &again) == HALFRAY_STATUS_SHORT_BUFFER);
    CHECK(halfray_baked_info(b.bytes, 0, &again) == HALFRAY_STATUS_SHORT_BUFFER);
    CHECK(memcmp(&again, &untouched, sizeof again) == 0);
    Buffer shifted = {aligned_bytes(b.len + 4), b.len};
    memcpy(shifted.bytes + 4, b.bytes, b.len);
    CHECK(halfray_baked_info(shifted.bytes + 4, b.len, &again) == HALFRAY_STATUS_MISALIGNED);

    /* halfray_load: NULLs, misaligned input, small scratch. */
    uint32_t scratch[1];
    HalfrayBvh bvh;
    memset(&bvh, 0, sizeof bvh);
    CHECK(halfray_load(NULL, b.len, scratch, 1, &bvh) == HALFRAY_STATUS_NULL);
    CHECK(halfray_load(b.bytes, b.len, scratch, 1, NULL) == HALFRAY_STATUS_NULL);
    CHECK(halfray_load(b.bytes, b.len, NULL, 1, &bvh) == HALFRAY_STATUS_NULL);
    CHECK(halfray_load(b.bytes, b.len, NULL, 0, &bvh) == HALFRAY_STATUS_SCRATCH_TOO_SMALL);
    CHECK(halfray_load(shifted.bytes + 4, b.len, scratch, 1, &bvh) == HALFRAY_STATUS_MISALIGNED);
    CHECK(halfray_load(b.bytes, b.len - 4, scratch, 1, &bvh) == HALFRAY_STATUS_SHORT_BUFFER);
    free(shifted.bytes);

    /* Corrupted baked data: each refused with the code of what was broken. */
    CHECK(load_corrupted(b, bad_magic) == HALFRAY_STATUS_NOT_BAKED);
    CHECK(load_corrupted(b, bad_reserved) == HALFRAY_STATUS_NOT_BAKED);
    CHECK(load_corrupted(b, bad_version) == HALFRAY_STATUS_VERSION);
    CHECK(get_u32(b.bytes + 32 + 28) == 0); /* the root is an inner node */
    CHECK(load_corrupted(b, root_child_before) == HALFRAY_STATUS_CHILD_OUT_OF_RANGE);
    CHECK(load_corrupted(b, root_child_past) == HALFRAY_STATUS_CHILD_OUT_OF_RANGE);
    CHECK(load_corrupted(b, root_box_nan) == HALFRAY_STATUS_BAD_BOX);
    CHECK(load_corrupted(b, root_box_inverted) == HALFRAY_STATUS_BAD_BOX);
    CHECK(load_corrupted(b, vertex_index_out_of_range) == HALFRAY_STATUS_BAD_TRIANGLE);
    CHECK(load_corrupted(b, vertex_nan) == HALFRAY_STATUS_BAD_TRIANGLE);
    CHECK(load_corrupted(b, index_repeated) == HALFRAY_STATUS_BAD_INDEX);
    CHECK(load_corrupted(b, index_out_of_range) == HALFRAY_STATUS_BAD_INDEX);

    /* Queries on an unloaded (zeroed) handle. */
    HalfrayStackEntry stack[HALFRAY_MAX_STACK_ENTRIES];
    HalfrayHit hit, sentinel;
    memset(&sentinel, 0x5A, sizeof sentinel);
    bool any = false;
    size_t entries = 999;
    HalfrayRay down = ray(0.25f, 0.25f, 5.0f, 0.0f, 0.0f, -1.0f);
    memset(&bvh, 0, sizeof bvh);
    CHECK(halfray_closest_hit(&bvh, &down, stack, 64, &hit) == HALFRAY_STATUS_NOT_LOADED);
    CHECK(halfray_any_hit(&bvh, &down, stack, 64, &any) == HALFRAY_STATUS_NOT_LOADED);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_NOT_LOADED && entries == 999);
    /* A handle whose first word is the tag's old constant and the rest made up ("HRAY",
     * then 0x41 bytes): not loaded (its tag does not check out), no read of the rest. */
    HalfrayBvh made_up;
    memset(&made_up, 0x41, sizeof made_up);
    made_up.opaque[0] = 0x48524159u;
    CHECK(halfray_closest_hit(&made_up, &down, stack, 64, &hit) == HALFRAY_STATUS_NOT_LOADED);
    CHECK(halfray_stack_entries(&made_up, &entries) == HALFRAY_STATUS_NOT_LOADED);

    /* Areas that overlap: refused before anything is written. The scratch inside the
     * buffer (the buffer unchanged), the handle inside the buffer or the scratch. */
    Buffer before = copy(b);
    CHECK(halfray_load(b.bytes, b.len, (uint32_t *)(void *)(b.bytes + 64), 1, &bvh) ==
          HALFRAY_STATUS_OVERLAP);
    CHECK(halfray_load(b.bytes, b.len, scratch, 1, (HalfrayBvh *)(void *)(b.bytes + 32)) ==
          HALFRAY_STATUS_OVERLAP);
    CHECK(memcmp(before.bytes, b.bytes, b.len) == 0);
    free(before.bytes);
    /* The scratch is dead before the handle is filled: those two may share memory. */
    _Alignas(HalfrayBvh) uint32_t wide_scratch[64];
    HalfrayBvh *inside = (HalfrayBvh *)(void *)(wide_scratch + 8);
    CHECK(halfray_load(b.bytes, b.len, wide_scratch, 64, inside) == HALFRAY_STATUS_OK);
    size_t inside_entries = 0;
    CHECK(halfray_stack_entries(inside, &inside_entries) == HALFRAY_STATUS_OK && inside_entries >= 1);

    /* A good load; the stack the tree needs. */
    CHECK(halfray_load(b.bytes, b.len, scratch, 1, &bvh) == HALFRAY_STATUS_OK);
    CHECK(halfray_stack_entries(NULL, &entries) == HALFRAY_STATUS_NULL);
    CHECK(halfray_stack_entries(&bvh, NULL) == HALFRAY_STATUS_NULL);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_OK);
    CHECK(entries >= 1 && entries <= HALFRAY_MAX_STACK_ENTRIES);

    /* A query whose stack overlaps the handle or the buffer: refused, the handle still
     * loaded and the answer untouched (the stack over the handle returned OK with a wrong
     * miss and destroyed the handle before). */
    hit = sentinel;
    CHECK(halfray_closest_hit(&bvh, &down, (HalfrayStackEntry *)(void *)&bvh, 16, &hit) ==
          HALFRAY_STATUS_OVERLAP);
    CHECK(halfray_closest_hit(&bvh, &down, (HalfrayStackEntry *)(void *)(b.bytes + 32), 4,
                              &hit) == HALFRAY_STATUS_OVERLAP);
    CHECK(halfray_any_hit(&bvh, &down, (HalfrayStackEntry *)(void *)&bvh, 16, &any) ==
          HALFRAY_STATUS_OVERLAP);
    CHECK(memcmp(&hit, &sentinel, sizeof hit) == 0);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_OK);
    /* A NULL stack whose count reaches the handle's address: OVERLAP (checked first), as
     * documented; with a count that reaches nothing, NULL. */
    CHECK(halfray_closest_hit(&bvh, &down, NULL, SIZE_MAX, &hit) == HALFRAY_STATUS_OVERLAP);
    CHECK(halfray_closest_hit(&bvh, &down, NULL, 1, &hit) == HALFRAY_STATUS_NULL);

    /* What a failed load leaves in a loaded handle: a NULL handle or an overlap, the tree
     * as it was; a NULL or misaligned buffer or scratch, "not loaded". */
    CHECK(halfray_load(b.bytes, b.len, (uint32_t *)(void *)(b.bytes + 64), 1, &bvh) ==
          HALFRAY_STATUS_OVERLAP);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_OK);
    CHECK(halfray_load(NULL, 0, scratch, 1, &bvh) == HALFRAY_STATUS_NULL);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_NOT_LOADED);
    CHECK(halfray_load(b.bytes, b.len, scratch, 1, &bvh) == HALFRAY_STATUS_OK);
    CHECK(halfray_load(b.bytes, b.len, (uint32_t *)(void *)((char *)scratch + 2), 1, &bvh) ==
          HALFRAY_STATUS_MISALIGNED);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_NOT_LOADED);
    CHECK(halfray_load(b.bytes, b.len, scratch, 1, &bvh) == HALFRAY_STATUS_OK);
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_OK);

    /* Closed-form answers. Straight down at (1/4, 1/4): the face x + y + z = 1 of
     * vertices +x, +y, +z (triangle 0) at z = 1/2, t = 4.5; b1 is y, b2 is z; Ng is
     * (+y - +x) x (+z - +x) = (1, 1, 1), against the ray: front face. */
    hit = sentinel;
    CHECK(halfray_closest_hit(&bvh, &down, stack, entries, &hit) == HALFRAY_STATUS_OK);
    CHECK(hit.primitive == 0);
    CHECK(fabsf(hit.t - 4.5f) <= 4.5f * 1e-6f);
    CHECK(fabsf(hit.b1 - 0.25f) <= 1e-6f && fabsf(hit.b2 - 0.5f) <= 1e-6f);
    CHECK(hit.ng[0] == 1.0f && hit.ng[1] == 1.0f && hit.ng[2] == 1.0f && hit.front_face);
    CHECK(halfray_any_hit(&bvh, &down, stack, entries, &any) == HALFRAY_STATUS_OK && any);
    /* From the centre, out through the same face: back face, t = 1 / (0.1 + 0.2 + 0.3). */
    HalfrayRay out = ray(0.0f, 0.0f, 0.0f, 0.1f, 0.2f, 0.3f);
    CHECK(halfray_closest_hit(&bvh, &out, stack, entries, &hit) == HALFRAY_STATUS_OK);
    CHECK(hit.primitive == 0 && !hit.front_face && fabsf(hit.t - 1.0f / 0.6f) <= 1e-5f);
    /* Through the vertex +z and through the midpoint of the edge (+x, +y): watertight, so
     * hits, and of the triangles sharing them at equal t the smallest index (0). */
    HalfrayRay vertex = ray(0.0f, 0.0f, 5.0f, 0.0f, 0.0f, -1.0f);
    CHECK(halfray_closest_hit(&bvh, &vertex, stack, entries, &hit) == HALFRAY_STATUS_OK);
    CHECK(hit.primitive == 0 && hit.t == 4.0f);
    HalfrayRay edge = ray(0.5f, 0.5f, 5.0f, 0.0f, 0.0f, -1.0f);
    CHECK(halfray_closest_hit(&bvh, &edge, stack, entries, &hit) == HALFRAY_STATUS_OK);
    CHECK(hit.primitive == 0 && hit.t == 5.0f);
    CHECK(halfray_any_hit(&bvh, &edge, stack, entries, &any) == HALFRAY_STATUS_OK && any);
    /* Misses: pointing away; stopping short (t_max 4 < 4.5); beside the octahedron. */
    HalfrayRay away = ray(0.25f, 0.25f, 5.0f, 0.0f, 0.0f, 1.0f);
    HalfrayRay short_ray = down;
    short_ray.t_max = 4.0f;
    HalfrayRay beside = ray(0.75f, 0.75f, 5.0f, 0.0f, 0.0f, -1.0f);
    const HalfrayRay *misses[] = {&away, &short_ray, &beside};
    for (int k = 0; k < 3; k++) {
        hit = sentinel;
        any = true;
        CHECK(halfray_closest_hit(&bvh, misses[k], stack, entries, &hit) == HALFRAY_STATUS_OK);
        CHECK(hit.primitive == HALFRAY_NO_HIT && hit.t == 0.0f);
        CHECK(halfray_any_hit(&bvh, misses[k], stack, entries, &any) == HALFRAY_STATUS_OK && !any);
    }

    /* Bad queries: NULLs, invalid rays, too small a stack; outputs untouched. */
    hit = sentinel;
    any = true;
    CHECK(halfray_closest_hit(NULL, &down, stack, entries, &hit) == HALFRAY_STATUS_NULL);
    CHECK(halfray_closest_hit(&bvh, NULL, stack, entries, &hit) == HALFRAY_STATUS_NULL);
    CHECK(halfray_closest_hit(&bvh, &down, NULL, entries, &hit) == HALFRAY_STATUS_NULL);
    CHECK(halfray_closest_hit(&bvh, &down, stack, entries, NULL) == HALFRAY_STATUS_NULL);
    CHECK(halfray_any_hit(NULL, &down, stack, entries, &any) == HALFRAY_STATUS_NULL);
    CHECK(halfray_any_hit(&bvh, NULL, stack, entries, &any) == HALFRAY_STATUS_NULL);
    CHECK(halfray_any_hit(&bvh, &down, NULL, entries, &any) == HALFRAY_STATUS_NULL);
    CHECK(halfray_any_hit(&bvh, &down, stack, entries, NULL) == HALFRAY_STATUS_NULL);
    /* Along x through the whole octahedron: both children of the root are entered, so one
     * waits on the traversal stack. */
    HalfrayRay through = ray(-5.0f, 0.01f, 0.02f, 1.0f, 0.0f, 0.0f);
    CHECK(halfray_closest_hit(&bvh, &through, NULL, 0, &hit) == HALFRAY_STATUS_STACK_TOO_SMALL);
    CHECK(halfray_any_hit(&bvh, &through, stack, 0, &any) == HALFRAY_STATUS_STACK_TOO_SMALL);
    HalfrayRay invalid[8];
    for (int k = 0; k < 8; k++) {
        invalid[k] = down;
    }
    invalid[0].origin[0] = NAN;
    invalid[1].direction[2] = NAN;
    invalid[2].origin[1] = INFINITY;
    invalid[3].direction[2] = 0.0f;
    invalid[4].t_min = NAN;
    invalid[5].t_max = NAN;
    invalid[6].t_min = INFINITY;
    invalid[7].t_min = 5.0f;
    invalid[7].t_max = 4.0f;
    for (int k = 0; k < 8; k++) {
        CHECK(halfray_closest_hit(&bvh, &invalid[k], stack, entries, &hit) ==
              HALFRAY_STATUS_INVALID_RAY);
        CHECK(halfray_any_hit(&bvh, &invalid[k], stack, entries, &any) ==
              HALFRAY_STATUS_INVALID_RAY);
    }
    CHECK(memcmp(&hit, &sentinel, sizeof hit) == 0 && any);

    /* A failed load into a loaded handle leaves it not loaded. */
    CHECK(halfray_load(b.bytes, 16, scratch, 1, &bvh) == HALFRAY_STATUS_SHORT_BUFFER);
    CHECK(halfray_closest_hit(&bvh, &down, stack, entries, &hit) == HALFRAY_STATUS_NOT_LOADED);
}

/* The firmware's rays on the torus, through the host library: the line mcu-host computed. */
static void torus(Buffer b, Buffer rays, const char *want) {
    HalfrayBakedInfo info;
    CHECK(halfray_baked_info(b.bytes, b.len, &info) == HALFRAY_STATUS_OK);
    uint32_t *scratch = calloc(info.scratch_words, sizeof *scratch);
    HalfrayBvh bvh;
    CHECK(halfray_load(b.bytes, b.len, scratch, info.scratch_words, &bvh) == HALFRAY_STATUS_OK);
    free(scratch); /* needed only during the load */
    size_t entries = 0;
    CHECK(halfray_stack_entries(&bvh, &entries) == HALFRAY_STATUS_OK);
    HalfrayStackEntry *stack = calloc(entries, sizeof *stack);
    Answers a = answers_new();
    for (size_t k = 0; k + sizeof(HalfrayRay) <= rays.len; k += sizeof(HalfrayRay)) {
        HalfrayRay r;
        memcpy(&r, rays.bytes + k, sizeof r);
        answers_ray(&a, &bvh, &r, stack, entries);
    }
    free(stack);
    char got[160];
    snprintf(got, sizeof got, "mcu-c: mps2-an386 %u queries hash %016llx hits %u leaks %u",
             (unsigned)a.queries, (unsigned long long)a.hash, (unsigned)a.hits,
             (unsigned)a.leaks);
    if (strcmp(got, want) != 0) {
        fprintf(stderr, "host: the torus rays' answers differ from halfray-core's\n  ffi:  %s\n  core: %s\n",
                got, want);
        failures++;
    }
    printf("host: %s (halfray-core on the host: the same)\n", got);
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: host OCTAHEDRON.bin TORUS.bin RAYS.bin 'mcu-c: ...'\n");
        return 2;
    }
    Buffer oct = read_file(argv[1]), tor = read_file(argv[2]), rays = read_file(argv[3]);
    octahedron(oct);
    forged_tag_in_shared_scratch();
    forged_address_in_shared_scratch(oct);
    hand_built_trees_get_their_codes();
    torus(tor, rays, argv[4]);
    free(oct.bytes);
    free(tor.bytes);
    free(rays.bytes);
    if (failures) {
        fprintf(stderr, "host: %d checks failed\n", failures);
        return 1;
    }
    printf("host: every check passed\n");
    return 0;
}
