/* font.c - see font.h. */
#include "font.h"

#include <dlfcn.h>
#include <fontconfig/fontconfig.h>
#include <ft2build.h>
#include FT_FREETYPE_H
#include <stdlib.h>
#include <string.h>

/* The entry points used, resolved from the shared libraries at open. */
#define CB_FT_FUNCTIONS(X) X(FT_Init_FreeType) X(FT_Done_FreeType) X(FT_New_Face) X(FT_Done_Face) X(FT_Set_Pixel_Sizes) X(FT_Load_Char)
#define CB_FC_FUNCTIONS(X) \
    X(FcInitLoadConfigAndFonts) X(FcConfigDestroy) X(FcNameParse) X(FcConfigSubstitute) X(FcDefaultSubstitute) \
    X(FcFontMatch) X(FcPatternGetString) X(FcPatternDestroy) X(FcFini)

struct cb_font {
    void *ft_library, *fc_library;
#define CB_FONT_MEMBER(name) __typeof__(&name) name;
    CB_FT_FUNCTIONS(CB_FONT_MEMBER)
    CB_FC_FUNCTIONS(CB_FONT_MEMBER)
#undef CB_FONT_MEMBER
    FT_Library ft;
    FT_Face face;
};

static bool resolve(cb_font *f, const char **missing)
{
    /* NODELETE, as for OSMesa: what the libraries keep past their cleanup stays attributable
     * to them (tests/lsan.supp). */
    *missing = "libfreetype.so.6";
    f->ft_library = dlopen("libfreetype.so.6", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!f->ft_library) return false;
    *missing = "libfontconfig.so.1";
    f->fc_library = dlopen("libfontconfig.so.1", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!f->fc_library) return false;
#define CB_FONT_RESOLVE(name, lib) \
    if (!(*(void **)&f->name = dlsym(f->lib, #name))) return *missing = #name, false;
#define CB_FT_RESOLVE(name) CB_FONT_RESOLVE(name, ft_library)
#define CB_FC_RESOLVE(name) CB_FONT_RESOLVE(name, fc_library)
    CB_FT_FUNCTIONS(CB_FT_RESOLVE)
    CB_FC_FUNCTIONS(CB_FC_RESOLVE)
#undef CB_FC_RESOLVE
#undef CB_FT_RESOLVE
#undef CB_FONT_RESOLVE
    return true;
}

/* The file of the best sans-serif match, copied into path. */
static bool find_sans(const cb_font *f, bool bold, char *path, size_t size)
{
    FcConfig *config = f->FcInitLoadConfigAndFonts();
    FcPattern *want = f->FcNameParse((const FcChar8 *)(bold ? "sans-serif:weight=bold" : "sans-serif"));
    bool found = false;
    if (config && want) {
        FcResult result;
        f->FcConfigSubstitute(config, want, FcMatchPattern);
        f->FcDefaultSubstitute(want);
        FcPattern *match = f->FcFontMatch(config, want, &result);
        FcChar8 *file = NULL;
        if (match && f->FcPatternGetString(match, FC_FILE, 0, &file) == FcResultMatch && file)
            found = (size_t)snprintf(path, size, "%s", (const char *)file) < size;
        if (match) f->FcPatternDestroy(match);
    }
    if (want) f->FcPatternDestroy(want);
    if (config) f->FcConfigDestroy(config);
    return found;
}

cb_font *cb_font_open(uint32_t pixels, bool bold, cb_error *err)
{
    cb_font *f = calloc(1, sizeof *f);
    const char *missing = "memory";
    char path[4096];
    if (!f || !resolve(f, &missing)) {
        cb_font_close(f);
        cb_fail(err, CB_ERR_INTERNAL, "labels need FreeType and fontconfig: %s not found (install libfreetype6 and "
                "libfontconfig1)", missing);
        return NULL;
    }
    if (!find_sans(f, bold, path, sizeof path) || f->FT_Init_FreeType(&f->ft) || f->FT_New_Face(f->ft, path, 0, &f->face) ||
        f->FT_Set_Pixel_Sizes(f->face, 0, pixels)) {
        cb_font_close(f);
        cb_fail(err, CB_ERR_INTERNAL, "labels need a sans-serif font that FreeType can read (install fonts-dejavu-core)");
        return NULL;
    }
    return f;
}

void cb_font_close(cb_font *f)
{
    if (!f) return;
    if (f->face) f->FT_Done_Face(f->face);
    if (f->ft) f->FT_Done_FreeType(f->ft);
    if (f->FcFini) f->FcFini(); /* fontconfig's global caches */
    if (f->fc_library) dlclose(f->fc_library);
    if (f->ft_library) dlclose(f->ft_library);
    free(f);
}

/* The next code point of UTF-8 text (U+FFFD for a broken sequence). */
static uint32_t next_code_point(const char **s)
{
    const unsigned char *p = (const unsigned char *)*s;
    uint32_t c = *p++;
    int extra = c >= 0xf0 ? 3 : c >= 0xe0 ? 2 : c >= 0xc0 ? 1 : 0;
    if (c >= 0x80 && !extra) c = 0xfffd;
    else if (extra) c &= 0x3f >> extra;
    for (; extra > 0; --extra, ++p) {
        if ((*p & 0xc0) != 0x80) {
            c = 0xfffd;
            break;
        }
        c = c << 6 | (*p & 0x3f);
    }
    *s = (const char *)p;
    return c;
}

static unsigned char *pixel(cb_canvas *cv, int x, int y)
{
    if (x < 0 || y < 0 || (uint32_t)x >= cv->width || (uint32_t)y >= cv->height) return NULL;
    uint32_t row = cv->bottom_up ? cv->height - 1 - (uint32_t)y : (uint32_t)y;
    return cv->rgba + ((size_t)row * cv->width + (uint32_t)x) * 4;
}

static int draw_glyphs(const cb_font *f, cb_canvas *cv, int x, int y, int max_x, const char *text, const uint8_t rgb[3])
{
    for (const char *s = text; *s;) {
        if (f->FT_Load_Char(f->face, next_code_point(&s), FT_LOAD_RENDER)) continue;
        FT_GlyphSlot g = f->face->glyph;
        int advance = (int)(g->advance.x >> 6);
        if (x + advance > max_x) break; /* whole glyphs only */
        for (unsigned r = 0; r < g->bitmap.rows; ++r)
            for (unsigned c = 0; c < g->bitmap.width; ++c) {
                unsigned a = g->bitmap.buffer[r * (unsigned)g->bitmap.pitch + c];
                unsigned char *p = a ? pixel(cv, x + g->bitmap_left + (int)c, y - g->bitmap_top + (int)r) : NULL;
                for (int k = 0; p && k < 3; ++k) p[k] = (unsigned char)((rgb[k] * a + p[k] * (255 - a) + 127) / 255);
            }
        x += advance;
    }
    return x;
}

/* A text that does not fit ends in an ellipsis, so a cut label reads as cut. */
int cb_font_draw(const cb_font *f, cb_canvas *cv, int x, int y, int max_x, const char *text, const uint8_t rgb[3])
{
    static const char ellipsis[] = "\xe2\x80\xa6";
    if (cb_font_width(f, text) <= max_x - x) return draw_glyphs(f, cv, x, y, max_x, text, rgb);
    x = draw_glyphs(f, cv, x, y, max_x - cb_font_width(f, ellipsis), text, rgb);
    return draw_glyphs(f, cv, x, y, max_x, ellipsis, rgb);
}

int cb_font_width(const cb_font *f, const char *text)
{
    int w = 0;
    for (const char *s = text; *s;)
        if (!f->FT_Load_Char(f->face, next_code_point(&s), FT_LOAD_DEFAULT)) w += (int)(f->face->glyph->advance.x >> 6);
    return w;
}

int cb_font_ascent(const cb_font *f) { return (int)((f->face->size->metrics.ascender + 63) >> 6); }
int cb_font_descent(const cb_font *f) { return (int)((-f->face->size->metrics.descender + 63) >> 6); }

void cb_canvas_fill(cb_canvas *cv, int x, int y, int w, int h, const uint8_t rgb[3])
{
    for (int yy = y; yy < y + h; ++yy)
        for (int xx = x; xx < x + w; ++xx) {
            unsigned char *p = pixel(cv, xx, yy);
            if (p) p[0] = rgb[0], p[1] = rgb[1], p[2] = rgb[2], p[3] = 255;
        }
}
