/* texel_geometry.c - where a palette's texels lie and how many there are: texels a bone takes
 * in each layout, bytes a texel takes in each precision, rows wrapped into blocks to fit a
 * texture-size limit, a row's bone's texel. A leaf: the encodings (palette_codec.c), the plan
 * (palette_plan.c) and the budget arithmetic (budget.c) all build on it, and it on none of them. */
#include "crowdbake/budget.h"
#include "crowdbake/palette.h"

uint32_t cb_layout_texels_per_bone(cb_layout l) { return l == CB_LAYOUT_MAT4 ? 4 : l == CB_LAYOUT_AFFINE ? 3 : 2; }
uint32_t cb_precision_texel_bytes(cb_precision p) { return p == CB_PRECISION_FLOAT ? 16 : 8; }

bool cb_wrap_rows(uint32_t row_texels, uint64_t rows, uint32_t max, cb_texture_geometry *out)
{
    out->width = out->height = out->blocks = 0;
    if (max < 1 || row_texels < 1 || rows < 1 || row_texels > max) return false;
    uint64_t blocks = (rows + max - 1) / max;
    if (blocks > max / row_texels) return false;
    out->blocks = (uint32_t)blocks;
    out->height = (uint32_t)((rows + blocks - 1) / blocks); /* balanced blocks: the least padding */
    out->width = out->blocks * row_texels;
    return true;
}

void cb_palette_texel_xy(const cb_palette *p, uint32_t row, uint32_t bone, uint32_t *x, uint32_t *y)
{
    *x = (row / p->height) * p->row_texels + bone * p->texels_per_bone;
    *y = row % p->height;
}
