/* bench_gl_check.c - bench_gl --check: the three methods' images of the same herd compared (bench_gl_check.h). */
#define GL_GLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_gl_check.h"
#include "bench_gl_mesh.h"
#include "bench_gl_tiers.h"

/* The LOD's tiers drawn apart against one draw finding each vertex's tier (the same decision: thresholds that put a
 * third of the 16 instances on each tier, far from any of them): the bytes of the two images that differ (*bytes, 0
 * for the same image), and the share of pixels where the LOD's image differs from every influence's (`all`). */
static double check_tiers(const scene *s, GLuint target, const float *vp, const unsigned char *all, long *bytes)
{
    scene t = *s;
    float lod[3] = {bench_herd_size(s->pal) * 0.5f * HEIGHT * hypotf(hypotf(vp[1], vp[5]), vp[9]), 0, 0};
    bench_split_tiers(s->instances, 8, 16, vp, lod);
    t.lod = true, t.lod_pixels[1] = lod[1], t.lod_pixels[0] = lod[2];
    unsigned char *img[2];
    for (int k = 0; k < 2; ++k) {
        t.tiers = k == 1;
        img[k] = malloc((size_t)WIDTH * HEIGHT * 4);
        bench_draw(&t, 1, 16, 0.77f, vp, target);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, target);
        glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, img[k]);
    }
    *bytes = 0;
    for (size_t i = 0; i < (size_t)WIDTH * HEIGHT * 4; ++i) *bytes += img[0][i] != img[1][i];
    bench_tiers tiers;
    bench_sort_by_tier(s->instances, 8, 16, vp, lod, s->order, &tiers);
    long covered;
    double vs_all = bench_image_difference(all, img[1], WIDTH, HEIGHT, &covered);
    printf("the LOD's tiers (%u / %u / %u instances on 1 / 2 / 4 influences, under %.1f / %.1f pixels tall) drawn apart vs "
           "in one draw: %ld bytes differ; vs every influence %.4f of the pixels differ\n", tiers.count[0], tiers.count[1],
           tiers.count[2], lod[2], lod[1], *bytes, vs_all);
    free(img[0]), free(img[1]);
    return vs_all;
}

/* 16 instances drawn by each method at the same time must give the same image; the VAT a
 * quarter second later (a runtime playing the wrong rows) must not. */
int bench_check_images(const scene *s, GLuint target)
{
    unsigned char *img[METHODS + 1];
    float vp[16];
    bench_place_herd(s, 16, vp);
    for (int m = 0; m <= METHODS; ++m) {
        img[m] = malloc((size_t)WIDTH * HEIGHT * 4);
        bench_draw(s, m < METHODS ? m : 2, 16, m < METHODS ? 0.77f : 0.77f + 0.25f, vp, target);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, target);
        glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, img[m]);
    }
    long covered;
    double late = bench_image_difference(img[0], img[3], WIDTH, HEIGHT, &covered), bones = bench_image_difference(img[0], img[1], WIDTH, HEIGHT, &covered),
           vat = bench_image_difference(img[0], img[2], WIDTH, HEIGHT, &covered);
    printf("16 instances on %s, %ld pixels covered: palette vs bone pass %.4f, palette vs VAT %.4f of the pixels differ; "
           "the VAT 0.25 s late %.4f\n", (const char *)glGetString(GL_RENDERER), covered, bones, vat, late);
    printf("rows at %g fps: the palette's error between rows %.4g, the VAT's own (half floats) %.4g units, of a model %.4g tall\n",
           s->pal->clips[0].fps, s->pal->visible_error, s->vat->max_error, s->pal->model_height);
    long tier_bytes = 0;
    double tiers_vs_all = check_tiers(s, target, vp, img[1], &tier_bytes);
    for (int m = 0; m <= METHODS; ++m) free(img[m]);
    bool ok = covered > 1000 && bones <= 0.01 && vat <= 0.01 && late > 0.05 && tier_bytes == 0 && (tiers_vs_all > 0 || !s->blended) &&
              glGetError() == GL_NO_ERROR;
    if (!ok) fprintf(stderr, "bench_gl: the images disagree (limits: 0.01 alike, > 0.05 0.25 s late, the LOD's tiers drawn "
                             "apart the same bytes as in one draw, some pixels off every influence's where a vertex blends)\n");
    return ok ? 0 : 1;
}
