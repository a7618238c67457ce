/* budget.c - see budget.h. */
#include "crowdbake/budget.h"

#include <ctype.h>

uint64_t cb_palette_texture_bytes(uint32_t bones, uint32_t rows, cb_layout layout, cb_precision precision, uint32_t max,
                                  cb_texture_geometry *g)
{
    if (!cb_wrap_rows(bones * cb_layout_texels_per_bone(layout), rows, max, g)) return 0;
    return (uint64_t)g->width * g->height * cb_precision_texel_bytes(precision);
}

const cb_vat_encoding cb_vat_encodings[CB_VAT_ENCODINGS] = {
    {"position RGBA16F + normal RGBA8", 8, 4},
    {"position + normal RGBA16F", 8, 8},
    {"position + normal RGBA32F", 16, 16},
};

bool cb_vat_geometry(uint64_t vertices, uint32_t frames, uint32_t max, cb_texture_geometry *g)
{
    g->width = g->height = g->blocks = 0;
    if (vertices == 0 || frames == 0 || max == 0) return false;
    uint32_t width = vertices < max ? (uint32_t)vertices : max;
    uint64_t rows_per_frame = (vertices + width - 1) / width;
    return cb_wrap_rows(width, rows_per_frame * frames, max, g);
}

uint64_t cb_vat_bytes(uint64_t vertices, uint32_t frames, const cb_vat_encoding *enc, const cb_texture_geometry *g)
{
    uint64_t texels = g->width ? (uint64_t)g->width * g->height : vertices * frames;
    return texels * (enc->position_bytes + enc->normal_bytes);
}

/* Sources in docs/budget.md. */
const cb_target_profile cb_profiles[] = {
    {"Steam Deck", 1ull << 30, 16384, "Valve: 1 GiB UMA frame buffer by default; Vulkan maxImageDimension2D 16384 (RADV)"},
    {"Desktop 4 GiB", 4ull << 30, 16384, "a 4 GiB discrete GPU; Direct3D 11 feature level 11_0 guarantees 16384"},
    {"Desktop 8 GiB", 8ull << 30, 16384, "an 8 GiB discrete GPU; Direct3D 11 feature level 11_0 guarantees 16384"},
    {"Mobile GLES 3.0", 512ull << 20, 2048, "OpenGL ES 3.0 guarantees MAX_TEXTURE_SIZE >= 2048; 512 MiB is a planning figure"},
    {"WebGL 2", 512ull << 20, 4096, "WebGL 2 devices commonly report 4096 or more (2048 guaranteed); 512 MiB planning figure"},
};
const uint32_t cb_profile_count = sizeof cb_profiles / sizeof cb_profiles[0];

/* Names compare case-insensitively with spaces, hyphens and underscores alike, so a command
 * line can say steam-deck for "Steam Deck". */
static bool same_profile_name(const char *a, const char *b)
{
    for (;; ++a, ++b) {
        char x = *a == '-' || *a == '_' ? ' ' : (char)tolower((unsigned char)*a);
        char y = *b == '-' || *b == '_' ? ' ' : (char)tolower((unsigned char)*b);
        if (x != y) return false;
        if (!x) return true;
    }
}

const cb_target_profile *cb_find_profile(const char *name)
{
    for (uint32_t i = 0; name && i < cb_profile_count; ++i)
        if (same_profile_name(cb_profiles[i].name, name)) return &cb_profiles[i];
    return NULL;
}
