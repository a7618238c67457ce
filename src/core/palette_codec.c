/* palette_codec.c - texels: encoding canonical rows in each layout and precision, decoding
 * them back as a shader reads them, and the value ranges u16 quantizes in. */
#include <stdlib.h>
#include <string.h>

#include "lanes.h"
#include "palette_bake.h"
#include "internal/plumbing.h"

/* Quantization arithmetic runs in double so it adds nothing to the half-step of the format. */
static double snorm16_decode(uint16_t u)
{
    double v = (int16_t)u / 32767.0;
    return v < -1 ? -1 : v;
}

static double unorm16_decode(uint16_t u, double lo, double hi) { return hi > lo ? lo + (hi - lo) * (u / 65535.0) : lo; }

/* The 4 * texels_per_bone values of one bone, in texel order, as floats. */
static void texel_values(const cb_palette *p, const float *v, float out[16])
{
    switch (p->layout) {
    case CB_LAYOUT_MAT4: /* texel k = column k */
        for (int k = 0; k < 4; ++k) {
            for (int r = 0; r < 3; ++r) out[k * 4 + r] = v[r * 4 + k];
            out[k * 4 + 3] = k == 3 ? 1.0f : 0.0f;
        }
        break;
    case CB_LAYOUT_AFFINE: /* texel k = row k */
        memcpy(out, v, 12 * sizeof(float));
        break;
    case CB_LAYOUT_QPOS:
        memcpy(out, v, 8 * sizeof(float));
        break;
    }
}

/* Which kind of u16 quantization each of a bone's values gets: 0 snorm over linear_range,
 * 1..3 unorm over the box axis (k - 1), 4 snorm as is (quaternions), 5 unorm over
 * [0, linear_range] (qpos scale), 6 a constant (mat4's last row). */
static int u16_kind(cb_layout layout, int i)
{
    if (layout == CB_LAYOUT_QPOS) return i < 4 ? 4 : i < 7 ? 1 + (i - 4) : 5;
    if (layout == CB_LAYOUT_AFFINE) return i % 4 == 3 ? 1 + i / 4 : 0;
    if (i % 4 == 3) return 6;                 /* mat4: w of each column */
    return i >= 12 ? 1 + (i - 12) : 0;        /* column 3 is the translation */
}

static double decode_u16(const cb_palette *p, int kind, uint16_t u)
{
    switch (kind) {
    case 0: return snorm16_decode(u) * p->linear_range;
    case 4: return snorm16_decode(u);
    case 5: return unorm16_decode(u, 0, p->linear_range);
    case 6: return u ? 1.0 : 0.0;
    default: return unorm16_decode(u, p->bounds_min[kind - 1], p->bounds_max[kind - 1]);
    }
}

static void store_le16(unsigned char *d, uint16_t v) { d[0] = (unsigned char)v, d[1] = (unsigned char)(v >> 8); }
static uint16_t load_le16(const unsigned char *d) { return (uint16_t)(d[0] | d[1] << 8); }

/* On a little-endian host a float's bytes are the texel's: one move, not four shifted bytes (a
 * float palette's encode and decode ran 4x longer byte by byte). */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define HOST_LITTLE_ENDIAN 1
#else
#define HOST_LITTLE_ENDIAN 0
#endif

static void store_le32f(unsigned char *d, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    if (HOST_LITTLE_ENDIAN) memcpy(d, &v, 4);
    else for (int i = 0; i < 4; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

static float load_le32f(const unsigned char *d)
{
    uint32_t v;
    if (HOST_LITTLE_ENDIAN) memcpy(&v, d, 4);
    else v = (uint32_t)d[0] | (uint32_t)d[1] << 8 | (uint32_t)d[2] << 16 | (uint32_t)d[3] << 24;
    float f;
    memcpy(&f, &v, 4);
    return f;
}

/* How each of a bone's values is quantized to u16: x = (v - offset) * scale, clamped to
 * [lo, hi], times `steps`, rounded; snorm values are stored as two's complement. */
typedef struct u16_slot {
    double offset, scale, lo, hi, steps;
} u16_slot;

static void u16_slots(const cb_palette *p, u16_slot slots[16])
{
    for (int i = 0; i < 16; ++i) {
        u16_slot *q = &slots[i];
        int kind = u16_kind(p->layout, i);
        double range = kind == 0 || kind == 5 ? p->linear_range : kind >= 1 && kind <= 3
                       ? (double)p->bounds_max[kind - 1] - p->bounds_min[kind - 1] : 1;
        bool snorm = kind == 0 || kind == 4;
        q->offset = kind >= 1 && kind <= 3 ? p->bounds_min[kind - 1] : 0;
        q->scale = range > 0 ? 1 / range : 0;
        q->lo = snorm ? -1 : 0;
        q->hi = 1;
        q->steps = snorm ? 32767 : 65535;
        if (kind == 6) q->offset = 0, q->scale = 1, q->lo = 0; /* mat4's constant 0/1 row */
    }
}

static inline uint16_t quantize(const u16_slot *q, double v)
{
    double x = (v - q->offset) * q->scale;
    x = x < q->lo ? q->lo : x; /* two selects, not nested ones: they compile to max and min, */
    x = x > q->hi ? q->hi : x; /* where the nested ones branch (and mispredict) */
    long n = lrint(x * q->steps);
    return (uint16_t)(int16_t)n; /* snorm: two's complement; unorm: 0..65535 fits */
}

/* quantize for four values at once, written to vectorize (one AVX2 operation each): the same
 * operations, and lrint's rounding (to nearest, ties to even) by adding and taking away 1.5 *
 * 2^52, exact for the |x| <= 65535 here; the same bits as quantize. */
typedef struct u16_lanes {
    double offset[4], scale[4], lo[4], hi[4], steps[4];
} u16_lanes;

static u16_lanes u16_lanes_of(const u16_slot *slots)
{
    u16_lanes q;
    for (int i = 0; i < 4; ++i)
        q.offset[i] = slots[i].offset, q.scale[i] = slots[i].scale, q.lo[i] = slots[i].lo, q.hi[i] = slots[i].hi,
        q.steps[i] = slots[i].steps;
    return q;
}

#if defined(__GNUC__) && HOST_LITTLE_ENDIAN
#define GCC_VECTORS 1
#else
#define GCC_VECTORS 0
#endif

#if GCC_VECTORS
/* GCC's vector types: the four values are one vector each step, and the last step packs the
 * low halves of the four integers into one 8-byte store (a loop over them, or memcpy from an
 * array, left each a separate extract and store). The same operations, the same bits. */
typedef float v4sf __attribute__((vector_size(16))); /* v4df and v4di: lanes.h */
typedef int32_t v4si __attribute__((vector_size(16)));
typedef int16_t v8hi __attribute__((vector_size(16)));
typedef int16_t v4hi __attribute__((vector_size(8)));
typedef uint16_t v4hu __attribute__((vector_size(8)));

static CB_CLONE_INLINE void quantize4(const u16_lanes *q, const float *v, unsigned char *d)
{
    v4sf f;
    v4df offset, scale, lo, hi, steps; /* (locals, not helpers: a 32-byte vector argument changes the ABI) */
    memcpy(&f, v, sizeof f);
    memcpy(&offset, q->offset, sizeof offset), memcpy(&scale, q->scale, sizeof scale);
    memcpy(&lo, q->lo, sizeof lo), memcpy(&hi, q->hi, sizeof hi), memcpy(&steps, q->steps, sizeof steps);
    v4df x = (__builtin_convertvector(f, v4df) - offset) * scale;
    v4di below = x < lo, above = x > hi; /* all ones where true: C has no ?: over vectors */
    x = (v4df)(((v4di)lo & below) | ((v4di)x & ~below));
    x = (v4df)(((v4di)hi & above) | ((v4di)x & ~above));
    v4si k = __builtin_convertvector((x * steps + CB_ROUND_MAGIC) - CB_ROUND_MAGIC, v4si);
    v8hi n = __builtin_shufflevector((v8hi)k, (v8hi)k, 0, 2, 4, 6, 0, 2, 4, 6); /* each low half: (uint16_t) */
    memcpy(d, &n, 8);
}
#else
static CB_CLONE_INLINE void quantize4(const u16_lanes *q, const float *v, unsigned char *d)
{
    for (int i = 0; i < 4; ++i) {
        double x = ((double)v[i] - q->offset[i]) * q->scale[i];
        x = x < q->lo[i] ? q->lo[i] : x;
        x = x > q->hi[i] ? q->hi[i] : x;
        store_le16(d + i * 2, (uint16_t)(int32_t)((x * q->steps[i] + CB_ROUND_MAGIC) - CB_ROUND_MAGIC));
    }
}
#endif

/* Encodes `count` rows of canonical floats into the texels of rows first, first + 1, ... */
void palette_encode_rows(cb_palette *p, const float *rows, uint32_t first, uint32_t count)
{
    uint32_t tb = cb_precision_texel_bytes(p->precision), nvalues = p->texels_per_bone * 4;
    u16_slot slots[16];
    u16_slots(p, slots);
    for (uint32_t r = first; r < first + count; ++r) {
        uint32_t x0, y;
        cb_palette_texel_xy(p, r, 0, &x0, &y);
        unsigned char *d = (unsigned char *)p->texels + ((size_t)y * p->width + x0) * tb;
        const float *row = rows + (size_t)(r - first) * p->bone_count * CANON(p->layout);
        if (HOST_LITTLE_ENDIAN && p->precision == CB_PRECISION_FLOAT && p->layout == CB_LAYOUT_QPOS && !p->positions_relative) {
            memcpy(d, row, (size_t)p->bone_count * 8 * sizeof(float)); /* qpos floats are their texels, in order */
            continue;
        }
        for (uint32_t j = 0; j < p->bone_count; ++j, d += (size_t)p->texels_per_bone * tb) {
            float vals[16], rel[12];
            const float *c = row + (size_t)j * CANON(p->layout), *o = p->position_offsets + (size_t)j * 3;
            if (p->positions_relative && p->layout != CB_LAYOUT_QPOS) { /* the translation: p = M b, less o */
                memcpy(rel, c, sizeof rel);
                for (int r = 0; r < 3; ++r) rel[r * 4 + 3] = (float)(row_position(c, p->bind_positions + (size_t)j * 3, r) - o[r]);
                c = rel;
            }
            texel_values(p, c, vals);
            for (int k = 0; p->positions_relative && p->layout == CB_LAYOUT_QPOS && k < 3; ++k) vals[4 + k] -= o[k];
            if (p->precision == CB_PRECISION_FLOAT)
                for (uint32_t i = 0; i < nvalues; ++i) store_le32f(d + i * 4, vals[i]);
            else if (p->precision == CB_PRECISION_HALF)
                for (uint32_t i = 0; i < nvalues; ++i) store_le16(d + i * 2, cb_float_to_half(vals[i]));
            else
                for (uint32_t i = 0; i < nvalues; ++i) store_le16(d + i * 2, quantize(&slots[i], vals[i]));
        }
    }
}

/* qpos in place, for u16 and half, whose positions wait for every clip's range or offset:
 * each bone's texel pair (16 bytes) holds its position and scale as 4 floats until then, and
 * its quaternion, which needs neither, is encoded at once into `stash` (8 bytes per bone and
 * row, half the texels' size): the bake keeps half the output's size more, not the output's
 * size again (a float copy of every position and scale). */
static unsigned char *qpos_texel(cb_palette *p, uint32_t row)
{
    uint32_t x0, y;
    cb_palette_texel_xy(p, row, 0, &x0, &y);
    return (unsigned char *)p->texels + ((size_t)y * p->width + x0) * 8; /* RGBA16: 8 bytes a texel */
}

/* One row's quaternions into the stash, as u16 (snorm, no range needed) or half; positions and
 * scales into the texels as floats. (Per precision, so that the loop carries no branch.) */
static CB_CLONE_INLINE void stage_row_u16(const u16_lanes *slots, const float *v, unsigned char *q, unsigned char *d,
                                          uint32_t bones)
{
    for (uint32_t j = 0; j < bones; ++j, v += 8, q += 8, d += 16) {
        quantize4(slots, v, q);
        memcpy(d, v + 4, 4 * sizeof(float));
    }
}

static void stage_row_half(const float *v, unsigned char *q, unsigned char *d, uint32_t bones)
{
    for (uint32_t j = 0; j < bones; ++j, v += 8, q += 8, d += 16) {
        for (uint32_t i = 0; i < 4; ++i) store_le16(q + i * 2, cb_float_to_half(v[i]));
        memcpy(d, v + 4, 4 * sizeof(float));
    }
}

CB_TARGET_CLONES
void palette_stage_qpos(cb_palette *p, const float *rows, unsigned char *stash, uint32_t first, uint32_t count)
{
    u16_slot slots[16];
    u16_slots(p, slots);
    u16_lanes quats = u16_lanes_of(slots);
    for (uint32_t r = first; r < first + count; ++r) {
        unsigned char *d = qpos_texel(p, r), *q = stash + (size_t)r * p->bone_count * 8;
        const float *row = rows + (size_t)(r - first) * p->bone_count * 8;
        if (p->precision == CB_PRECISION_U16) stage_row_u16(&quats, row, q, d, p->bone_count);
        else stage_row_half(row, q, d, p->bone_count);
    }
}

/* The position and scale staged in the texels (see palette_stage_qpos). */
static void staged_values(const unsigned char *d, float out[4]) { memcpy(out, d, 4 * sizeof(float)); }

/* One row: the staged values read before their texel pair is overwritten, encoded into its
 * second texel, the stashed quaternion copied into its first. */
static CB_CLONE_INLINE void finish_row_u16(const u16_lanes *slots, const unsigned char *q, unsigned char *d, uint32_t bones)
{
    for (uint32_t j = 0; j < bones; ++j, q += 8, d += 16) {
        float v[4];
        staged_values(d, v);
        quantize4(slots, v, d + 8);
        memcpy(d, q, 8);
    }
}

static void finish_row_half(const float *offsets, const unsigned char *q, unsigned char *d, uint32_t bones)
{
    for (uint32_t j = 0; j < bones; ++j, q += 8, d += 16, offsets += 3) {
        float v[4];
        staged_values(d, v);
        for (uint32_t i = 0; i < 3; ++i) store_le16(d + 8 + i * 2, cb_float_to_half(v[i] - offsets[i]));
        store_le16(d + 14, cb_float_to_half(v[3]));
        memcpy(d, q, 8);
    }
}

CB_TARGET_CLONES
void palette_finish_qpos(cb_palette *p, const unsigned char *stash, uint32_t first, uint32_t count)
{
    u16_slot slots[16];
    u16_slots(p, slots);
    u16_lanes positions = u16_lanes_of(slots + 4);
    for (uint32_t r = first; r < first + count; ++r) {
        unsigned char *d = qpos_texel(p, r);
        const unsigned char *q = stash + (size_t)r * p->bone_count * 8;
        if (p->precision == CB_PRECISION_U16) finish_row_u16(&positions, q, d, p->bone_count);
        else finish_row_half(p->position_offsets, q, d, p->bone_count);
    }
}

/* mat4 and affine in place, for u16 and half: a bone's 12 canonical floats wait for every
 * clip's range or offset split between its texels (as many floats as they hold: mat4 8,
 * affine 6) and the stash (the rest), then go through the ordinary encoder row by row. */
static uint32_t texel_floats(const cb_palette *p) { return p->texels_per_bone * 8 / 4; } /* 8-byte texels */
uint32_t palette_stash_bytes(const cb_palette *p) { return p->layout == CB_LAYOUT_QPOS ? 8 : (12 - texel_floats(p)) * 4; }

static unsigned char *row_texels(const cb_palette *p, uint32_t row)
{
    uint32_t x0, y;
    cb_palette_texel_xy(p, row, 0, &x0, &y);
    return (unsigned char *)p->texels + ((size_t)y * p->width + x0) * 8;
}

void palette_stage_rows(cb_palette *p, const float *rows, unsigned char *stash, uint32_t first, uint32_t count)
{
    uint32_t in_texels = texel_floats(p), in_stash = 12 - in_texels, bone_bytes = p->texels_per_bone * 8;
    for (uint32_t r = first; r < first + count; ++r) {
        unsigned char *d = row_texels(p, r), *q = stash + (size_t)r * p->bone_count * in_stash * 4;
        const float *v = rows + (size_t)(r - first) * p->bone_count * 12;
        for (uint32_t j = 0; j < p->bone_count; ++j, v += 12, d += bone_bytes, q += in_stash * 4) {
            memcpy(d, v, in_texels * sizeof(float));
            memcpy(q, v + in_texels, in_stash * sizeof(float));
        }
    }
}

/* Row r's canonical floats back from its texels and the stash (before the texels are encoded). */
void palette_gather_row(const cb_palette *p, const unsigned char *stash, uint32_t r, float *row)
{
    uint32_t in_texels = texel_floats(p), in_stash = 12 - in_texels, bone_bytes = p->texels_per_bone * 8;
    const unsigned char *d = row_texels(p, r), *q = stash + (size_t)r * p->bone_count * in_stash * 4;
    for (uint32_t j = 0; j < p->bone_count; ++j, row += 12, d += bone_bytes, q += in_stash * 4) {
        memcpy(row, d, in_texels * sizeof(float));
        memcpy(row + in_texels, q, in_stash * sizeof(float));
    }
}

/* Relative half palettes: each bone's position offset, the centre of the box of its positions
 * over every row. A half float's step grows with the value; positions less the centre stay
 * within half the bone's reach (Cow: 0.60 -> 0.32 mm/m; less its bind position, a body that
 * falls or travels still lands far from it). From the values staged in the texels (and for
 * mat4 and affine the stash), row by row, so that the texels are read once, in order. */
bool palette_position_offsets(cb_palette *p, const unsigned char *stash)
{
    double *box = malloc((size_t)p->bone_count * 6 * sizeof(double)); /* lo[3], hi[3] per bone */
    float *row = p->layout == CB_LAYOUT_QPOS ? NULL : malloc((size_t)p->bone_count * 12 * sizeof(float));
    if (!box || (p->layout != CB_LAYOUT_QPOS && !row)) return free(box), free(row), false;
    for (uint32_t j = 0; j < p->bone_count; ++j)
        for (int k = 0; k < 3; ++k) box[j * 6 + k] = INFINITY, box[j * 6 + 3 + k] = -INFINITY;
    for (uint32_t r = 0; r < p->rows; ++r) {
        const unsigned char *d = p->layout == CB_LAYOUT_QPOS ? qpos_texel(p, r) : NULL;
        if (row) palette_gather_row(p, stash, r, row);
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            float staged[4];
            const float *v = staged;
            if (d) staged_values(d + (size_t)j * 16, staged);
            else v = row + (size_t)j * 12;
            double *lo = box + j * 6, *hi = lo + 3;
            for (int k = 0; k < 3; ++k) {
                double x = d ? v[k] : row_position(v, p->bind_positions + (size_t)j * 3, k);
                lo[k] = x < lo[k] ? x : lo[k], hi[k] = x > hi[k] ? x : hi[k];
            }
        }
    }
    for (uint32_t j = 0; j < p->bone_count; ++j)
        for (int k = 0; k < 3; ++k)
            p->position_offsets[(size_t)j * 3 + k] = p->rows ? (float)(0.5 * (box[j * 6 + k] + box[j * 6 + 3 + k])) : 0;
    free(box), free(row);
    return true;
}

/* One bone's values from its texels at d; kinds[i] is u16_kind of value i (u16 only). */
static void decode_bone(const cb_palette *p, const unsigned char *d, const int *kinds, uint32_t bone, double v[16])
{
    if (p->precision == CB_PRECISION_U16 && p->bone_space == CB_BONE_SPACE_LOCAL) { /* the bone's own ranges */
        const float *e = p->bone_ranges + (size_t)bone * 8;
        for (int i = 0; i < 4; ++i) v[i] = snorm16_decode(load_le16(d + i * 2));
        for (int i = 0; i < 3; ++i) v[4 + i] = unorm16_decode(load_le16(d + 8 + i * 2), e[i], e[4 + i]);
        v[7] = unorm16_decode(load_le16(d + 14), 0, e[3]);
        return;
    }
    if (p->precision == CB_PRECISION_U16 && p->layout == CB_LAYOUT_QPOS) {
        /* The default encoding, written out (decode_u16's arithmetic for kinds 4, 1..3 and 5). */
        for (int i = 0; i < 4; ++i) v[i] = snorm16_decode(load_le16(d + i * 2));
        for (int i = 0; i < 3; ++i) v[4 + i] = unorm16_decode(load_le16(d + 8 + i * 2), p->bounds_min[i], p->bounds_max[i]);
        v[7] = unorm16_decode(load_le16(d + 14), 0, p->linear_range);
        for (int k = 0; p->positions_relative && k < 3; ++k) v[4 + k] += p->position_offsets[(size_t)bone * 3 + k];
        return;
    }
    for (uint32_t i = 0; i < p->texels_per_bone * 4; ++i) {
        if (p->precision == CB_PRECISION_FLOAT)
            v[i] = load_le32f(d + i * 4);
        else if (p->precision == CB_PRECISION_HALF)
            v[i] = cb_half_to_float(load_le16(d + i * 2));
        else
            v[i] = decode_u16(p, kinds[i], load_le16(d + i * 2));
    }
    /* The position values: qpos's texel 1, mat4's column 3, affine's w of each row. */
    static const int at[3][3] = {{12, 13, 14}, {3, 7, 11}, {4, 5, 6}};
    for (int k = 0; p->positions_relative && k < 3; ++k) v[at[p->layout][k]] += p->position_offsets[(size_t)bone * 3 + k];
}

static void value_kinds(cb_layout layout, int kinds[16])
{
    for (int i = 0; i < 16; ++i) kinds[i] = u16_kind(layout, i);
}

void cb_palette_decode_values(const cb_palette *p, const void *texels, uint32_t row, uint32_t bone, double v[16])
{
    uint32_t tb = cb_precision_texel_bytes(p->precision), x, y;
    int kinds[16];
    value_kinds(p->layout, kinds);
    cb_palette_texel_xy(p, row, bone, &x, &y);
    decode_bone(p, (const unsigned char *)texels + ((size_t)y * p->width + x) * tb, kinds, bone, v);
}

/* decode_bone's qpos/u16 arithmetic for a whole row, four values at a time (snorm16_decode's
 * and unorm16_decode's operations in their order, so the same doubles), which vectorizes. Local
 * rows: each bone in its own ranges (its range table entry). */
#if GCC_VECTORS
static CB_CLONE_INLINE void decode_qpos_u16_row(const cb_palette *p, const unsigned char *d, double *values)
{
    v4df lo = {p->bounds_min[0], p->bounds_min[1], p->bounds_min[2], 0}, minus1 = {-1, -1, -1, -1};
    v4df hi = {p->bounds_max[0], p->bounds_max[1], p->bounds_max[2], p->linear_range}, span = hi - lo;
    v4di keep = hi > lo; /* all ones where the range is not a point */
    bool local = p->bone_space == CB_BONE_SPACE_LOCAL;
    for (uint32_t j = 0; j < p->bone_count; ++j, d += 16) {
        double *v = values + (size_t)j * 16;
        if (local) {
            const float *e = p->bone_ranges + (size_t)j * 8;
            lo = (v4df){e[0], e[1], e[2], 0}, hi = (v4df){e[4], e[5], e[6], e[3]}, span = hi - lo, keep = hi > lo;
        }
        v4hi qs;
        v4hu us;
        memcpy(&qs, d, sizeof qs), memcpy(&us, d + 8, sizeof us);
        v4df q = __builtin_convertvector(qs, v4df) / 32767.0;
        v4df x = lo + span * (__builtin_convertvector(us, v4df) / 65535.0);
        v4di below = q < minus1;
        q = (v4df)(((v4di)minus1 & below) | ((v4di)q & ~below));
        x = (v4df)(((v4di)x & keep) | ((v4di)lo & ~keep));
        memcpy(v, &q, sizeof q), memcpy(v + 4, &x, sizeof x);
        for (int k = 0; p->positions_relative && k < 3; ++k) v[4 + k] += p->position_offsets[(size_t)j * 3 + k];
    }
}
#else
static CB_CLONE_INLINE void decode_qpos_u16_row(const cb_palette *p, const unsigned char *d, double *values)
{
    double lo[4] = {p->bounds_min[0], p->bounds_min[1], p->bounds_min[2], 0}, span[4], keep[4];
    double hi[4] = {p->bounds_max[0], p->bounds_max[1], p->bounds_max[2], p->linear_range};
    for (uint32_t j = 0; j < p->bone_count; ++j, d += 16) {
        double *v = values + (size_t)j * 16;
        if (p->bone_space == CB_BONE_SPACE_LOCAL) {
            const float *e = p->bone_ranges + (size_t)j * 8;
            double bone_lo[4] = {e[0], e[1], e[2], 0}, bone_hi[4] = {e[4], e[5], e[6], e[3]};
            memcpy(lo, bone_lo, sizeof lo), memcpy(hi, bone_hi, sizeof hi);
        }
        for (int i = 0; i < 4; ++i) span[i] = hi[i] - lo[i], keep[i] = hi[i] > lo[i] ? 1 : 0;
        uint16_t u[8];
        for (int i = 0; i < 8; ++i) u[i] = load_le16(d + i * 2);
        for (int i = 0; i < 4; ++i) {
            double q = (int16_t)u[i] / 32767.0, x = lo[i] + span[i] * (u[4 + i] / 65535.0);
            v[i] = q < -1 ? -1 : q;
            v[4 + i] = keep[i] != 0 ? x : lo[i];
        }
        for (int k = 0; p->positions_relative && k < 3; ++k) v[4 + k] += p->position_offsets[(size_t)j * 3 + k];
    }
}
#endif

CB_TARGET_CLONES
void palette_decode_row_values(const cb_palette *p, uint32_t row, double *values)
{
    uint32_t tb = cb_precision_texel_bytes(p->precision), x, y;
    int kinds[16];
    value_kinds(p->layout, kinds);
    cb_palette_texel_xy(p, row, 0, &x, &y); /* a row's bones lie side by side */
    const unsigned char *d = (const unsigned char *)p->texels + ((size_t)y * p->width + x) * tb;
    if (p->precision == CB_PRECISION_U16 && p->layout == CB_LAYOUT_QPOS) {
        decode_qpos_u16_row(p, d, values);
        return;
    }
    if (p->precision == CB_PRECISION_FLOAT && !p->positions_relative) { /* decode_bone's floats, as they are */
        for (uint32_t j = 0, n = p->texels_per_bone * 4; j < p->bone_count; ++j, d += (size_t)n * 4)
            for (uint32_t i = 0; i < n; ++i) values[(size_t)j * 16 + i] = load_le32f(d + i * 4);
        return;
    }
    for (uint32_t j = 0; j < p->bone_count; ++j, d += (size_t)p->texels_per_bone * tb) decode_bone(p, d, kinds, j, values + (size_t)j * 16);
}

void cb_palette_decode(const cb_palette *p, const void *texels, uint32_t row, uint32_t bone, double out[16])
{
    double v[16];
    if (p->bone_space == CB_BONE_SPACE_LOCAL) palette_local_composed(p, texels, row, row, 0, bone, v); /* composed */
    else cb_palette_decode_values(p, texels, row, bone, v);
    cb_palette_values_to_matrix(p, bone, v, out);
}

void cb_palette_values_to_matrix(const cb_palette *p, uint32_t bone, const double v[16], double out[16])
{
    if (p->layout != CB_LAYOUT_QPOS) cb_mat4_identity(out); /* qpos: cb_mat4_from_trs sets all 16 */
    if (p->layout == CB_LAYOUT_MAT4) {
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 3; ++r) out[c * 4 + r] = v[c * 4 + r];
    } else if (p->layout == CB_LAYOUT_AFFINE) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) out[c * 4 + r] = v[r * 4 + c];
    }
    if (p->layout != CB_LAYOUT_QPOS && p->positions_relative) { /* the translation holds p = M b: t = p - A b */
        const float *b = p->bind_positions + (size_t)bone * 3;
        cb_vec3 ab = cb_mat4_transform_dir(out, (cb_vec3){b[0], b[1], b[2]});
        out[12] -= ab.x, out[13] -= ab.y, out[14] -= ab.z;
    } else if (p->layout == CB_LAYOUT_QPOS) {
        /* v' = p + s * rotate(q, v - b)  =>  A = s R(q), t = p - A b */
        cb_quat q = cb_quat_normalize((cb_quat){v[0], v[1], v[2], v[3]});
        double s = v[7];
        cb_vec3 one = {s, s, s};
        cb_mat4_from_trs(out, (cb_vec3){0, 0, 0}, q, one);
        const float *b = p->bind_positions + (size_t)bone * 3;
        cb_vec3 ab = cb_mat4_transform_dir(out, (cb_vec3){b[0], b[1], b[2]});
        out[12] = v[4] - ab.x, out[13] = v[5] - ab.y, out[14] = v[6] - ab.z;
    }
}

void palette_merge_ranges(cb_palette *p, const value_range *clips)
{
    value_range all;
    range_reset(&all);
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        for (int k = 0; k < 3; ++k) {
            if (clips[c].lo[k] < all.lo[k]) all.lo[k] = clips[c].lo[k];
            if (clips[c].hi[k] > all.hi[k]) all.hi[k] = clips[c].hi[k];
        }
        if (clips[c].linear > all.linear) all.linear = clips[c].linear;
    }
    bool empty = !(all.lo[0] <= all.hi[0]);
    for (int k = 0; k < 3; ++k) p->bounds_min[k] = empty ? 0 : all.lo[k], p->bounds_max[k] = empty ? 0 : all.hi[k];
    p->linear_range = all.linear;
}

