/* cmd_inspect.c - `crowdbake inspect FILE`: a palette's header and clip table, and one frame
 * decoded back to 4x4 matrices. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake_pal.h"
#include "crowdbake/exr.h"
#include "internal/json.h"
#include "crowdbake/ktx2.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/palette.h"
#include "cli.h"

const char cmd_inspect_usage[] =
    "usage: crowdbake inspect FILE.pal|FILE.ktx2|FILE.exr [--json] [--clip NAME --frame I] [--no-verify] [-q] [-v]\n\n"
    "Validates a palette (sizes, offsets and the checksum) and prints its header and clip table;\n"
    "a .ktx2 shows the same header values and clip table as the .pal of the same bake.\n"
    "with --clip and --frame, decodes that frame back to 4x4 joint matrices (column-major), to\n"
    "compare with 'crowdbake sample'.\n";


/* What inspect prints of a palette, from a .pal or a .ktx2 of the same bake: the same header
 * values and clip table (the .pal adds its version, payload and checksum). */
typedef struct inspected {
    const char *path;
    const cbpal_file *pal; /* a .pal: its container's own fields; NULL for a .ktx2 */
    const cb_palette *view;
    const void *texels;
    bool in_place;
    uint64_t input_hash;
    float speed_reference;
    const char *const *bone_names;
} inspected;

/* The rates the clips were baked at: "fps 30" when every clip has the file's rate, else "fps
 * 24-48 per clip" (an error-bounded bake chooses each clip's); and how many clips' rows are
 * fitted to the runtime's blend. */
static const char *clip_rates(const cb_palette *p, char *buf, size_t size)
{
    double lo = p->clip_count ? INFINITY : p->fps, hi = p->clip_count ? 0 : p->fps;
    uint32_t fitted = 0;
    for (uint32_t i = 0; i < p->clip_count; ++i)
        lo = fmin(lo, (float)p->clips[i].fps), hi = fmax(hi, (float)p->clips[i].fps), fitted += p->clips[i].fitted;
    if (lo == hi) snprintf(buf, size, "fps %g", lo);
    else snprintf(buf, size, "fps %g-%g per clip", lo, hi);
    snprintf(buf + strlen(buf), size - strlen(buf), ", %u of %u clip%s fitted", fitted, p->clip_count,
             p->clip_count == 1 ? "" : "s");
    return buf;
}

/* Local rows (.pal version 6): what the runtime does with them, and the bone range table in brief:
 * the widest box of local positions and the scales stored. */
static void print_local_text(const cb_palette *p)
{
    uint32_t widest = 0;
    double span = -1, smin = INFINITY, smax = 0;
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        const float *e = p->bone_ranges + (size_t)j * 8;
        double s = fmax(fmax(e[4] - e[0], e[5] - e[1]), e[6] - e[2]);
        if (s > span) span = s, widest = j;
        smin = fmin(smin, e[3]), smax = fmax(smax, e[3]);
    }
    printf("  bones: local (composed by the runtime); range table: %u bones, positions within (%g, %g, %g)..(%g, %g, %g), "
           "widest %g (bone %u), scale_max %g..%g\n", p->bone_count, p->bounds_min[0], p->bounds_min[1], p->bounds_min[2],
           p->bounds_max[0], p->bounds_max[1], p->bounds_max[2], span, widest, smin, smax);
}

static void print_header_text(const inspected *in)
{
    const cb_palette *p = in->view;
    if (in->pal) {
        const cbpal_header *h = &in->pal->header;
        printf("%s: crowdbake palette v%u, ", in->path, h->version);
    } else {
        printf("%s: KTX2 palette, ", in->path);
    }
    printf("%s/%s, %u bones x %u texels, %u rows in %u block%s of %u, %ux%u texels\n", cb_layout_name(p->layout),
           cb_precision_name(p->precision), p->bone_count, p->texels_per_bone, p->rows, p->blocks, p->blocks == 1 ? "" : "s",
           p->height, p->width, p->height);
    if (in->pal) {
        const cbpal_header *h = &in->pal->header;
        printf("  payload %llu bytes at offset %llu%s, ", (unsigned long long)h->payload_size,
               (unsigned long long)h->payload_offset, h->flags & CBPAL_FLAG_ZSTD ? " (zstd)" : "");
    } else {
        printf("  texels %zu bytes, ", p->texel_bytes);
    }
    char rates[96];
    printf("%s, speed reference %g units/s, max error %g (model height %g)\n", clip_rates(p, rates, sizeof rates),
           in->speed_reference, (float)p->max_error, (float)p->model_height);
    printf("  input hash %016llx", (unsigned long long)in->input_hash);
    if (in->pal) printf(", checksum %016llx", (unsigned long long)in->pal->header.checksum);
    printf("%s%s\n", in->in_place ? ", root motion removed" : "",
           p->fitted ? ", every clip's rows fitted to the linear blend" : "");
    if (p->bone_space == CB_BONE_SPACE_LOCAL) print_local_text(p);
}

static void print_clip_table(const inspected *in)
{
    const cb_palette *p = in->view;
    /* In place, the clip table holds the root's travel that was measured and taken out of the
     * rows (the game moves the instance by it); kept, the rows carry it and the table has 0. */
    /* The name column as wide as the longest name, so exported names ("Armature|Walk") keep the
     * table aligned. */
    int name_width = 24;
    for (uint32_t i = 0; i < p->clip_count; ++i)
        if ((int)strlen(p->clips[i].name) > name_width) name_width = (int)strlen(p->clips[i].name);
    printf("  %-*s %9s %7s %8s %9s %-8s %-7s %s\n", name_width, "clip", "first row", "frames", "fps", "length s", "loops",
           "rows", in->in_place ? "root velocity removed (units/s)" : "root motion");
    for (uint32_t i = 0; i < p->clip_count; ++i) {
        const cb_palette_clip *c = &p->clips[i];
        printf("  %-*s %9u %7u %8.3f %9.4f %-8s %-7s ", name_width, c->name, c->first_row, c->frames, (float)c->fps,
               (float)c->duration, c->loops ? "loop" : "one-shot", c->step ? "held" : c->fitted ? "fitted" : "sampled");
        /* A one-shot with nothing removed keeps its travel in the rows: a bake that put only its
         * loops in place (root_motion loops-in-place, the default where a loop travels). */
        bool moved = c->root_velocity[0] != 0 || c->root_velocity[1] != 0 || c->root_velocity[2] != 0;
        if (!in->in_place || (!c->loops && !moved)) {
            printf("in the rows\n");
            continue;
        }
        double v[3], scale = 0;
        for (int k = 0; k < 3; ++k) scale = fmax(scale, fabs(c->root_velocity[k]));
        for (int k = 0; k < 3; ++k) /* float noise of a measured zero reads as 0 */
            v[k] = fabs(c->root_velocity[k]) <= 1e-6 * fmax(scale, 1) ? 0 : c->root_velocity[k];
        printf("(%.4g, %.4g, %.4g), speed %.4g\n", v[0], v[1], v[2], sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
    }
    for (uint32_t i = 0; i < p->clip_count; ++i) /* timed rows (.pal version 7): the grid and the map */
        if (p->clips[i].timed)
            printf("  %s: timed, %u rows on %u cells at %g cells/s (the map: %u row%s before row %u)\n", p->clips[i].name,
                   p->clips[i].frames, p->clips[i].cells, (float)p->clips[i].cell_rate, p->clips[i].map_rows,
                   p->clips[i].map_rows == 1 ? "" : "s", p->clips[i].first_row);
}

static void print_clips_json(cb_json *j, const cb_palette *p)
{
    cb_json_array(j, "clips");
    for (uint32_t i = 0; i < p->clip_count; ++i) {
        const cb_palette_clip *c = &p->clips[i];
        cb_json_object(j, NULL);
        cb_json_string(j, "name", c->name);
        cb_json_int(j, "first_row", c->first_row);
        cb_json_int(j, "frames", c->frames);
        cb_json_number(j, "fps", (float)c->fps);
        cb_json_number(j, "duration", (float)c->duration);
        cb_json_bool(j, "loops", c->loops);
        cb_json_bool(j, "fitted_rows", c->fitted);
        if (c->step) cb_json_bool(j, "step_rows", true); /* held, not blended (clip flag bit 2); absent: blended */
        if (c->timed) { /* timed rows (clip flag bit 3); absent: uniform */
            cb_json_bool(j, "timed_rows", true);
            cb_json_int(j, "cells", c->cells);
            cb_json_number(j, "cell_rate", (float)c->cell_rate);
            cb_json_int(j, "map_rows", c->map_rows);
        }
        cb_json_inline_array(j, "root_velocity");
        for (int k = 0; k < 3; ++k) cb_json_number(j, NULL, c->root_velocity[k]);
        cb_json_end(j);
        cb_json_end(j);
    }
    cb_json_end(j);
}

static void print_frame_json(cb_json *j, const inspected *in, int clip, long frame)
{
    const cb_palette_clip *c = &in->view->clips[clip];
    cb_json_string(j, "clip", c->name);
    cb_json_int(j, "frame", frame);
    cb_json_array(j, "joints");
    for (uint32_t b = 0; b < in->view->bone_count; ++b) {
        double m[16];
        cb_palette_decode(in->view, in->texels, c->first_row + (uint32_t)frame, b, m);
        cb_json_inline_array(j, NULL);
        for (int k = 0; k < 16; ++k) cb_json_number(j, NULL, m[k]);
        cb_json_end(j);
    }
    cb_json_end(j);
}

static void print_local_json(cb_json *j, const cb_palette *p)
{
    cb_json_string(j, "bone_space", "local");
    cb_json_array(j, "bone_ranges"); /* the range table: per bone pos_min, pos_max, scale_max */
    for (uint32_t b = 0; b < p->bone_count; ++b) {
        const float *e = p->bone_ranges + (size_t)b * 8;
        cb_json_inline_array(j, NULL);
        for (int k = 0; k < 7; ++k) cb_json_number(j, NULL, e[k < 3 ? k : k < 6 ? k + 1 : 3]);
        cb_json_end(j);
    }
    cb_json_end(j);
}

/* The same keys for a .pal and a .ktx2, in the same order; version, zstd and payload_* are the
 * .pal container's own. */
static void print_json(const inspected *in, int clip, long frame)
{
    const cb_palette *p = in->view;
    const cbpal_header *h = in->pal ? &in->pal->header : NULL;
    cb_json j;
    cb_json_init(&j, stdout);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "file", in->path);
    if (h) cb_json_int(&j, "version", h->version);
    cb_json_string(&j, "layout", cb_layout_name(p->layout));
    cb_json_string(&j, "precision", cb_precision_name(p->precision));
    cb_json_int(&j, "bones", p->bone_count);
    cb_json_int(&j, "texels_per_bone", p->texels_per_bone);
    cb_json_int(&j, "rows", p->rows);
    cb_json_int(&j, "width", p->width);
    cb_json_int(&j, "height", p->height);
    cb_json_int(&j, "blocks", p->blocks);
    if (p->bone_space == CB_BONE_SPACE_LOCAL) print_local_json(&j, p); /* absent: global, as every file before v6 */
    if (h) cb_json_bool(&j, "zstd", (h->flags & CBPAL_FLAG_ZSTD) != 0);
    cb_json_string(&j, "root_motion", cb_root_motion_name(in->in_place ? CB_ROOT_MOTION_IN_PLACE : CB_ROOT_MOTION_KEEP));
    cb_json_bool(&j, "fitted_rows", p->fitted); /* every clip fitted; each clip says its own below */
    uint32_t fitted = 0;
    double lo = p->clip_count ? INFINITY : p->fps, hi = p->clip_count ? 0 : p->fps;
    for (uint32_t i = 0; i < p->clip_count; ++i)
        fitted += p->clips[i].fitted, lo = fmin(lo, (float)p->clips[i].fps), hi = fmax(hi, (float)p->clips[i].fps);
    cb_json_int(&j, "fitted_clips", fitted);
    cb_json_number(&j, "fps", (float)p->fps);
    cb_json_inline_array(&j, "clip_fps_range"); /* the clips' own rates: an error-bounded bake chooses each */
    cb_json_number(&j, NULL, lo);
    cb_json_number(&j, NULL, hi);
    cb_json_end(&j);
    cb_json_number(&j, "speed_reference", in->speed_reference);
    cb_json_number(&j, "max_error", (float)p->max_error);
    if (h) cb_json_int(&j, "payload_offset", (long long)h->payload_offset);
    if (h) cb_json_int(&j, "payload_bytes", (long long)h->payload_size);
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)in->input_hash);
    cb_json_string(&j, "input_hash", hash);
    print_clips_json(&j, p);
    cb_json_array(&j, "bones");
    for (uint32_t i = 0; i < p->bone_count; ++i) cb_json_string(&j, NULL, in->bone_names[i]);
    cb_json_end(&j);
    if (clip >= 0) print_frame_json(&j, in, clip, frame);
    cb_json_end(&j);
}

static int inspect_exr(const char *path, bool json)
{
    cb_error err = {0};
    cb_exr_image img;
    if (cb_exr_read(path, &img, &err)) return cli_report(&err);
    if (json) {
        cb_json j;
        cb_json_init(&j, stdout);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "file", path);
        cb_json_string(&j, "layout", img.layout);
        cb_json_string(&j, "precision", cb_precision_name(img.precision));
        cb_json_int(&j, "bones", img.bones);
        cb_json_int(&j, "rows", img.rows);
        cb_json_int(&j, "width", img.width);
        cb_json_int(&j, "height", img.height);
        cb_json_int(&j, "blocks", img.blocks);
        cb_json_int(&j, "clips", img.clips);
        cb_json_end(&j);
    } else {
        printf("%s: OpenEXR palette, %s/%s, %d bones, %d rows in %d block(s), %ux%u texels, %d clips "
               "(see exrheader for the crowdbake.* attributes)\n",
               path, img.layout, cb_precision_name(img.precision), img.bones, img.rows, img.blocks, img.width, img.height,
               img.clips);
    }
    cb_exr_image_free(&img);
    return 0;
}

/* A .pal, mapped (its checksum verified unless no_verify), as a palette view and its bones' names. */
static cb_status open_pal(const char *path, bool no_verify, cbpal_file *f, cb_palette *view, const char ***bones,
                          cb_error *err)
{
    char msg[512];
    if (cbpal_open(path, no_verify ? 0 : CBPAL_VERIFY_CHECKSUM, f, msg, sizeof msg) != 0)
        return cb_fail(err, CB_ERR_INPUT, "%s", msg);
    *bones = calloc(f->header.bone_count + 1, sizeof **bones);
    if (!*bones || cb_palette_view(f, view, err)) {
        if (!err->status) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        free(*bones), cbpal_close(f);
        return err->status;
    }
    for (uint32_t i = 0; i < f->header.bone_count; ++i) {
        cbpal_bone b;
        cbpal_get_bone(f, i, &b);
        (*bones)[i] = b.name;
    }
    return CB_OK;
}

/* --clip NAME --frame I: the clip's index, or -1 with *err set. */
static int find_frame(const inspected *in, const char *clip_name, const char *frame_text, unsigned *frame, cb_error *err)
{
    const cb_palette *p = in->view;
    char why[512];
    int clip = p->clip_count ? cli_match_clip(clip_name, &p->clips[0].name, p->clip_count, sizeof p->clips[0], why, sizeof why)
                             : (snprintf(why, sizeof why, "the palette has no clip"), -1);
    if (clip < 0) return cb_fail(err, CB_ERR_SETTINGS, "%s: --clip %s: %s", in->path, clip_name, why), -1;
    if (!cli_parse_u32(frame_text, frame) || *frame >= p->clips[clip].frames)
        return cb_fail(err, CB_ERR_SETTINGS, "%s: clip '%s' has %u frames; --frame %s is not one of them", in->path, clip_name,
                       p->clips[clip].frames, frame_text), -1;
    return clip;
}

int cmd_inspect(int argc, char **argv)
{
    cli_output out;
    if (cli_take_output(&argc, argv, &out)) return CLI_EXIT_USAGE;
    const char *path = NULL, *clip_name = NULL, *frame_text = NULL;
    bool json = false, no_verify = false, help;
    const cli_option options[] = {{"--json", NULL, NULL, &json},
                                  {"--clip", "NAME", &clip_name, NULL},
                                  {"--frame", "I", &frame_text, NULL},
                                  {"--no-verify", NULL, NULL, &no_verify}};
    int rc = cli_parse(argc, argv, options, 4, &path, 1, 1, &help);
    if (help) return fputs(cmd_inspect_usage, stdout), fputs(cli_output_usage, stdout), 0;
    if (rc) return rc;
    if (!clip_name != !frame_text) return cli_usage_error("inspect", "--clip and --frame go together");
    size_t n = strlen(path);
    if (n >= 4 && strcmp(path + n - 4, ".exr") == 0) return inspect_exr(path, json);
    double t0 = cli_seconds();
    cb_error err = {0};
    inspected in = {.path = path};
    cbpal_file f;
    cb_ktx2_palette ktx2;
    cb_palette view;
    const char **pal_bones = NULL;
    bool is_ktx2 = cli_file_kind_of(path) == CLI_FILE_KTX2, opened = false;
    if (is_ktx2) {
        if (cb_ktx2_read_palette(path, &ktx2, &err)) return cli_report(&err);
        in.view = &ktx2.palette, in.texels = ktx2.palette.texels, in.in_place = ktx2.in_place;
        in.input_hash = ktx2.input_hash, in.speed_reference = ktx2.speed_reference, in.bone_names = ktx2.bone_names;
        opened = true;
    } else if (open_pal(path, no_verify, &f, &view, &pal_bones, &err) == CB_OK) {
        const cbpal_header *h = &f.header;
        in.pal = &f, in.view = &view, in.texels = f.texels, in.in_place = (h->flags & CBPAL_FLAG_IN_PLACE) != 0;
        in.input_hash = h->input_hash, in.speed_reference = h->speed_reference, in.bone_names = pal_bones;
        opened = true;
    }
    if (opened)
        cli_verbose(&out, "read %s in %.3f s: %s/%s, %u bones, %u rows, %u clip%s", path, cli_seconds() - t0,
                    cb_layout_name(in.view->layout), cb_precision_name(in.view->precision), in.view->bone_count, in.view->rows,
                    in.view->clip_count, in.view->clip_count == 1 ? "" : "s");
    int clip = -1;
    unsigned frame = 0;
    if (opened && clip_name) clip = find_frame(&in, clip_name, frame_text, &frame, &err);
    if (opened && !err.status) {
        if (json || clip >= 0) print_json(&in, clip, (long)frame);
        else print_header_text(&in), print_clip_table(&in);
    }
    if (is_ktx2 && opened) cb_ktx2_palette_free(&ktx2);
    else if (opened) free(pal_bones), cb_palette_view_free(&view), cbpal_close(&f);
    return err.status ? cli_report(&err) : 0;
}
