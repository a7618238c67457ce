/* font.h - text for pictures: the system's sans-serif font (found by fontconfig) rasterized by
 * FreeType into an RGBA image. Both libraries are opened when a text is first drawn, like
 * OSMesa for previews, so no other command pays for loading them. */
#ifndef CB_FONT_H
#define CB_FONT_H

#include <stdint.h>

#include "crowdbake/core.h"

typedef struct cb_font cb_font;

/* A font of `pixels` em size, bold or regular; NULL with *err set when fontconfig, FreeType
 * or a sans-serif font is missing. */
cb_font *cb_font_open(uint32_t pixels, bool bold, cb_error *err);
void cb_font_close(cb_font *font);

/* An RGBA8 image, rows top to bottom unless bottom_up (OpenGL's order). */
typedef struct cb_canvas {
    unsigned char *rgba;
    uint32_t width, height;
    bool bottom_up;
} cb_canvas;

/* Draws UTF-8 text with its baseline at y, from x, within [x, max_x): whole glyphs, and a text
 * too long for it cut short with an ellipsis. Returns the x after it. Pixels outside the
 * canvas are skipped. */
int cb_font_draw(const cb_font *font, cb_canvas *canvas, int x, int y, int max_x, const char *text, const uint8_t rgb[3]);
/* The text's width in pixels. */
int cb_font_width(const cb_font *font, const char *text);
/* Pixels from the baseline up to the top of the tallest capital, and down below it. */
int cb_font_ascent(const cb_font *font);
int cb_font_descent(const cb_font *font);

/* A filled rectangle, clipped to the canvas. */
void cb_canvas_fill(cb_canvas *canvas, int x, int y, int w, int h, const uint8_t rgb[3]);

#endif
