/* crowdbake_pal_runtime.h - part of crowdbake_pal.h (which includes it in its implementation;
 * do not include it alone): a bone's matrix at a clip time, decoded and blended exactly as the
 * shipped shaders (runtimes/glsl/crowdbake_palette.glsl) decode and blend two rows, so that a
 * game attaches a prop to a bone where the GPU draws it. Public domain / MIT-0. */
#ifndef CROWDBAKE_PAL_RUNTIME_H
#define CROWDBAKE_PAL_RUNTIME_H

static float cbpal__half(uint16_t h) /* the exponent rebiased; zero and subnormals are m 2^-24 */
{
    uint32_t e = (h >> 10) & 0x1fu, m = h & 0x3ffu, bits = (uint32_t)(h & 0x8000u) << 16 | m << 13;
    float f;
    bits |= e == 31 ? 0x7f800000u : (e + 112) << 23;
    memcpy(&f, &bits, 4);
    return e ? f : (h & 0x8000u ? -1.0f : 1.0f) * (float)m / 16777216.0f;
}
static float cbpal__snorm(uint16_t u) { return fmaxf((float)((int32_t)u - (u >= 32768u ? 65536 : 0)) / 32767.0f, -1.0f); }

/* Texel k of a bone in a row, as the GLSL's cb_texel decodes it. */
static void cbpal__texel(const cbpal_file *f, uint32_t row, uint32_t bone, uint32_t k, float t[4])
{
    const cbpal_header *h = &f->header;
    uint32_t x, y;
    cbpal_texel_xy(h, row, bone, &x, &y);
    const unsigned char *p = (const unsigned char *)f->texels + ((size_t)y * h->width + x + k) * h->texel_bytes;
    uint16_t u[4];
    memcpy(u, p, 8);
    const float *lo = h->bounds_min, *hi = h->bounds_max, range = h->linear_range;
    int box = (h->layout == CBPAL_LAYOUT_QPOS && k == 1) || (h->layout == CBPAL_LAYOUT_MAT4 && k == 3), i;
    float scale = h->layout == CBPAL_LAYOUT_QPOS ? 1.0f : range; /* quaternions are plain snorm */
    if (h->precision == CBPAL_PRECISION_FLOAT) memcpy(t, p, 16);
    for (i = 0; i < 4 && h->precision == CBPAL_PRECISION_HALF; ++i) t[i] = cbpal__half(u[i]);
    if (h->precision != CBPAL_PRECISION_U16) return;
    if (h->range_table_offset && k == 1) { /* local rows: the bone's own ranges */
        const unsigned char *e = f->data + h->range_table_offset + (uint64_t)bone * CBPAL_RANGE_SIZE;
        for (i = 0; i < 3; ++i) t[i] = cbpal__f32(e + 4 * i) + (cbpal__f32(e + 16 + 4 * i) - cbpal__f32(e + 4 * i)) * ((float)u[i] / 65535.0f);
        t[3] = cbpal__f32(e + 12) * (float)u[3] / 65535.0f;
        return;
    }
    for (i = 0; i < 3; ++i) t[i] = box ? lo[i] + (hi[i] - lo[i]) * ((float)u[i] / 65535.0f) : cbpal__snorm(u[i]) * scale;
    if (h->layout == CBPAL_LAYOUT_QPOS) t[3] = k == 0 ? cbpal__snorm(u[3]) : range * (float)u[3] / 65535.0f;
    else if (h->layout == CBPAL_LAYOUT_AFFINE) t[3] = lo[k] + (hi[k] - lo[k]) * ((float)u[3] / 65535.0f);
    else t[3] = k == 3 ? 1.0f : 0.0f;
}

/* Texel k of a bone, mixed between two rows with weight fr on the second (qpos: the rotation the
 * shorter way). */
static void cbpal__mix(const cbpal_file *f, uint32_t r0, uint32_t r1, float fr, uint32_t bone, uint32_t k, float t[4])
{
    float a[4], b[4];
    cbpal__texel(f, r0, bone, k, a);
    cbpal__texel(f, r1, bone, k, b);
    int flip = f->header.layout == CBPAL_LAYOUT_QPOS && k == 0 && a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0;
    for (int i = 0; i < 4; ++i) t[i] = a[i] + ((flip ? -b[i] : b[i]) - a[i]) * fr;
}

/* A timed clip's rows at `time` (pal-format.md "Timed rows", as cb_runtime_frame_in): its cell on
 * the grid, and the two rows and weights the map holds there, the weight linear within the cell. */
static int cbpal__timed_frame(const cbpal_file *f, const cbpal_clip *c, double time, uint32_t *r0, uint32_t *r1, float *fr)
{
    double n = c->cells, u = time * c->cell_rate, cell;
    float m[4];
    if (!isfinite(u)) return -1;
    if (c->flags & CBPAL_CLIP_LOOPS) {
        u -= n * floor(u / n);
        if (!(u >= 0 && u < n)) u = 0; /* rounding at the wrap */
        cell = floor(u);
    } else {
        u = u < 0 ? 0 : u > n ? n : u;
        cell = fmin(floor(u), n - 1);
    }
    cbpal__map_texel(f, c->first_row, c->map_rows, (uint32_t)cell, m);
    int held = (c->flags & CBPAL_CLIP_STEP) != 0; /* the map's r0 alone */
    *r0 = c->first_row + (uint32_t)m[0];
    *r1 = held ? *r0 : c->first_row + (uint32_t)m[1];
    *fr = held ? 0.0f : (float)(m[2] + (m[3] - m[2]) * (u - cell));
    return 0;
}

/* The rows at `time` and the weight of the second, as the GLSL's cb_frame picks them: a
 * CBPAL_CLIP_STEP clip's row alone (weight 0 on the same row); a timed clip's through its map. */
static int cbpal__frame(const cbpal_file *f, const cbpal_clip *c, double time, uint32_t *r0, uint32_t *r1, float *fr)
{
    if (c->flags & CBPAL_CLIP_TIMED) return cbpal__timed_frame(f, c, time, r0, r1, fr);
    double frames = c->frames, fpos = time * c->fps, f0, f1;
    if (!isfinite(fpos)) return -1;
    if (c->flags & CBPAL_CLIP_LOOPS) fpos -= frames * floor(fpos / frames);
    else fpos = fpos < 0 ? 0 : fpos > frames - 1 ? frames - 1 : fpos;
    if (!(fpos >= 0 && fpos < frames)) fpos = 0; /* rounding at the wrap */
    f0 = floor(fpos), f1 = f0 + 1 < frames ? f0 + 1 : (c->flags & CBPAL_CLIP_LOOPS) ? 0 : f0; /* a loop's last row blends into its first */
    if (c->flags & CBPAL_CLIP_STEP) f1 = f0, fpos = f0; /* held: no blend across a step */
    *fr = (float)(fpos - f0), *r0 = c->first_row + (uint32_t)f0, *r1 = c->first_row + (uint32_t)f1;
    return 0;
}

/* Local rows: a bone's two texels blended (the quaternion normalised: nlerp). */
static void cbpal__local(const cbpal_file *f, uint32_t r0, uint32_t r1, float fr, uint32_t bone, float t[2][4])
{
    cbpal__mix(f, r0, r1, fr, bone, 0, t[0]);
    cbpal__mix(f, r0, r1, fr, bone, 1, t[1]);
    float n = sqrtf(t[0][0] * t[0][0] + t[0][1] * t[0][1] + t[0][2] * t[0][2] + t[0][3] * t[0][3]);
    for (int i = 0; i < 4; ++i) t[0][i] = n > 0 ? t[0][i] / n : (i == 3 ? 1.0f : 0.0f);
}

/* Local rows: the bone's blended local transform composed with each ancestor's, walking up its
 * chain (composition is associative: acc = A_parent after acc, A about the parent's bind position
 * b: q = q_a q, s = s_a s, p = p_a + s_a rotate(q_a, p - b)). Into t as a global qpos bone's
 * texels. At most bone_count steps (the reader refused cycles). */
static void cbpal__composed(const cbpal_file *f, uint32_t r0, uint32_t r1, float fr, uint32_t bone, float t[2][4])
{
    cbpal_bone b;
    float a[2][4];
    cbpal__local(f, r0, r1, fr, bone, t);
    cbpal_get_bone(f, bone, &b);
    for (uint32_t steps = 0; b.parent >= 0 && steps < f->header.bone_count; ++steps) {
        uint32_t up = (uint32_t)b.parent;
        cbpal__local(f, r0, r1, fr, up, a);
        cbpal_get_bone(f, up, &b);
        const float *q = a[0];
        float v[3] = {t[1][0] - b.bind_position[0], t[1][1] - b.bind_position[1], t[1][2] - b.bind_position[2]};
        float u[3] = {q[1] * v[2] - q[2] * v[1], q[2] * v[0] - q[0] * v[2], q[0] * v[1] - q[1] * v[0]}; /* q.xyz x v */
        float uu[3] = {q[1] * u[2] - q[2] * u[1], q[2] * u[0] - q[0] * u[2], q[0] * u[1] - q[1] * u[0]};
        float x = t[0][0], y = t[0][1], z = t[0][2], w = t[0][3];
        for (int i = 0; i < 3; ++i) t[1][i] = a[1][i] + a[1][3] * (v[i] + 2 * (q[3] * u[i] + uu[i]));
        t[1][3] *= a[1][3];
        t[0][0] = q[3] * x + q[0] * w + q[1] * z - q[2] * y, t[0][1] = q[3] * y - q[0] * z + q[1] * w + q[2] * x;
        t[0][2] = q[3] * z + q[0] * y - q[1] * x + q[2] * w, t[0][3] = q[3] * w - q[0] * x - q[1] * y - q[2] * z;
    }
}

int cbpal_bone_matrix(const cbpal_file *f, uint32_t clip, double time, uint32_t bone, float m[16])
{
    cbpal_clip c;
    cbpal_bone b;
    uint32_t r0, r1, k;
    float fr, t[4][4] = {{0}}, p[3];
    if (cbpal_get_clip(f, clip, &c) || cbpal_get_bone(f, bone, &b) || cbpal__frame(f, &c, time, &r0, &r1, &fr)) return -1;
    if (f->header.range_table_offset) cbpal__composed(f, r0, r1, fr, bone, t); /* normalised below */
    for (k = 0; !f->header.range_table_offset && k < f->header.texels_per_bone; ++k) cbpal__mix(f, r0, r1, fr, bone, k, t[k]);
    memset(m, 0, 16 * sizeof *m), m[15] = 1.0f;
    if (f->header.layout == CBPAL_LAYOUT_QPOS) {
        float n = sqrtf(t[0][0] * t[0][0] + t[0][1] * t[0][1] + t[0][2] * t[0][2] + t[0][3] * t[0][3]);
        float x = t[0][0] / n, y = t[0][1] / n, z = t[0][2] / n, w = t[0][3] / n;
        float r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),  /* column 0 */
                      2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),  /* column 1 */
                      2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)}; /* column 2 */
        for (k = 0; k < 9; ++k) m[k / 3 * 4 + k % 3] = t[1][3] * r[k]; /* scale */
        memcpy(p, t[1], sizeof p);
    } else {
        for (k = 0; k < 12; ++k) /* affine: texel k is row k; mat4: texel k is column k */
            m[k / 3 * 4 + k % 3] = f->header.layout == CBPAL_LAYOUT_AFFINE ? t[k % 3][k / 3] : t[k / 3][k % 3];
        for (k = 0; k < 3; ++k) p[k] = f->header.layout == CBPAL_LAYOUT_AFFINE ? t[k][3] : t[3][k];
    }
    /* qpos and relative positions: A (v - b) + p, with p stored less the bone's position offset. */
    int about_bind = f->header.layout == CBPAL_LAYOUT_QPOS || (f->header.flags & CBPAL_FLAG_POSITIONS_RELATIVE);
    for (k = 0; k < 3; ++k) {
        m[12 + k] = p[k] + b.position_offset[k];
        if (about_bind) m[12 + k] -= m[k] * b.bind_position[0] + m[4 + k] * b.bind_position[1] + m[8 + k] * b.bind_position[2];
    }
    return 0;
}

int cbpal_timed_map(const cbpal_file *f, uint32_t clip, uint32_t cell, float out[4])
{
    cbpal_clip c;
    if (cbpal_get_clip(f, clip, &c) || !(c.flags & CBPAL_CLIP_TIMED) || cell >= c.cells) return -1;
    cbpal__map_texel(f, c.first_row, c.map_rows, cell, out);
    return 0;
}

int cbpal_clip_frame(const cbpal_file *f, uint32_t clip, double time, uint32_t *row0, uint32_t *row1, float *fr)
{
    cbpal_clip c;
    return cbpal_get_clip(f, clip, &c) || cbpal__frame(f, &c, time, row0, row1, fr) ? -1 : 0;
}

float cbpal_row_travel(const cbpal_file *f, uint32_t row)
{
    const cbpal_header *h = &f->header;
    return h->travel_table_offset && row < h->rows ? cbpal__f32(f->data + h->travel_table_offset + (uint64_t)row * 4) : 0.0f;
}

int cbpal_travel_offset(const cbpal_file *f, uint32_t clip, double time, float out[3])
{
    cbpal_clip c;
    uint32_t r0, r1, k;
    float fr;
    if (cbpal_get_clip(f, clip, &c) || cbpal__frame(f, &c, time, &r0, &r1, &fr)) return -1;
    float a = cbpal_row_travel(f, r0), o = a + (cbpal_row_travel(f, r1) - a) * fr;
    for (k = 0; k < 3; ++k) out[k] = o * c.travel_heading[k];
    return 0;
}

#endif /* CROWDBAKE_PAL_RUNTIME_H */
