/* cmd_inspect.c - `crowdbake inspect FILE`: a palette's header and clip table, and one frame
 * decoded back to 4x4 matrices. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake_pal.h"
#include "crowdbake/exr.h"
#include "crowdbake/json.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/palette.h"
#include "cli.h"

const char cmd_inspect_usage[] =
    "usage: crowdbake inspect FILE.pal|FILE.exr [--json] [--clip NAME --frame I] [--no-verify]\n\n"
    "Validates a palette (sizes, offsets and the checksum) and prints its header and clip table;\n"
    "with --clip and --frame, decodes that frame back to 4x4 joint matrices (column-major), to\n"
    "compare with 'crowdbake sample'.\n";

static const char *layout_str(uint32_t l) { return cb_layout_name((cb_layout)l); }
static const char *precision_str(uint32_t p) { return cb_precision_name((cb_precision)p); }

static void print_pal_text(const char *path, const cbpal_file *f)
{
    const cbpal_header *h = &f->header;
    printf("%s: crowdbake palette v%u, %s/%s, %u bones x %u texels, %u rows in %u block%s of %u, %ux%u texels\n", path,
           h->version, layout_str(h->layout), precision_str(h->precision), h->bone_count, h->texels_per_bone, h->rows,
           h->blocks, h->blocks == 1 ? "" : "s", h->height, h->width, h->height);
    printf("  payload %llu bytes at offset %llu%s, fps %g, speed reference %g m/s, max error %g (model height %g)\n",
           (unsigned long long)h->payload_size, (unsigned long long)h->payload_offset,
           h->flags & CBPAL_FLAG_ZSTD ? " (zstd)" : "", h->fps, h->speed_reference, h->max_error, h->model_height);
    printf("  input hash %016llx, checksum %016llx%s%s\n", (unsigned long long)h->input_hash,
           (unsigned long long)h->checksum, h->flags & CBPAL_FLAG_IN_PLACE ? ", root motion removed" : "",
           h->flags & CBPAL_FLAG_FITTED_ROWS ? ", every clip's rows fitted to the linear blend" : "");
    bool in_place = (h->flags & CBPAL_FLAG_IN_PLACE) != 0;
    /* In place, the clip table holds the root's travel that was measured and taken out of the
     * rows (the game moves the instance by it); kept, the rows carry it and the table has 0. */
    /* The name column as wide as the longest name, so exported names ("Armature|Walk") keep the
     * table aligned. */
    int name_width = 24;
    for (uint32_t i = 0; i < h->clip_count; ++i) {
        cbpal_clip c;
        cbpal_get_clip(f, i, &c);
        int len = (int)strlen(c.name);
        if (len > name_width) name_width = len;
    }
    printf("  %-*s %9s %7s %8s %9s %-8s %-7s %s\n", name_width, "clip", "first row", "frames", "fps", "length s", "loops",
           "rows", in_place ? "root velocity removed (units/s)" : "root motion");
    for (uint32_t i = 0; i < h->clip_count; ++i) {
        cbpal_clip c;
        cbpal_get_clip(f, i, &c);
        printf("  %-*s %9u %7u %8.3f %9.4f %-8s %-7s ", name_width, c.name, c.first_row, c.frames, c.fps, c.duration,
               c.flags & CBPAL_CLIP_LOOPS ? "loop" : "one-shot", c.flags & CBPAL_CLIP_FITTED ? "fitted" : "sampled");
        if (!in_place) {
            printf("in the rows\n");
            continue;
        }
        double v[3], scale = 0;
        for (int k = 0; k < 3; ++k) scale = fmax(scale, fabs(c.root_velocity[k]));
        for (int k = 0; k < 3; ++k) /* float noise of a measured zero reads as 0 */
            v[k] = fabs(c.root_velocity[k]) <= 1e-6 * fmax(scale, 1) ? 0 : c.root_velocity[k];
        printf("(%.4g, %.4g, %.4g), speed %.4g\n", v[0], v[1], v[2], sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
    }
}

static void print_pal_json(const char *path, const cbpal_file *f, const cb_palette *view, int clip, long frame)
{
    const cbpal_header *h = &f->header;
    cb_json j;
    cb_json_init(&j, stdout);
    cb_json_object(&j, NULL);
    cb_json_string(&j, "file", path);
    cb_json_int(&j, "version", h->version);
    cb_json_string(&j, "layout", layout_str(h->layout));
    cb_json_string(&j, "precision", precision_str(h->precision));
    cb_json_int(&j, "bones", h->bone_count);
    cb_json_int(&j, "texels_per_bone", h->texels_per_bone);
    cb_json_int(&j, "rows", h->rows);
    cb_json_int(&j, "width", h->width);
    cb_json_int(&j, "height", h->height);
    cb_json_int(&j, "blocks", h->blocks);
    cb_json_bool(&j, "zstd", (h->flags & CBPAL_FLAG_ZSTD) != 0);
    cb_json_string(&j, "root_motion", cb_root_motion_name(h->flags & CBPAL_FLAG_IN_PLACE ? CB_ROOT_MOTION_IN_PLACE : CB_ROOT_MOTION_KEEP));
    cb_json_bool(&j, "fitted_rows", (h->flags & CBPAL_FLAG_FITTED_ROWS) != 0);
    cb_json_number(&j, "fps", h->fps);
    cb_json_number(&j, "speed_reference", h->speed_reference);
    cb_json_number(&j, "max_error", h->max_error);
    cb_json_int(&j, "payload_offset", (long long)h->payload_offset);
    cb_json_int(&j, "payload_bytes", (long long)h->payload_size);
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)h->input_hash);
    cb_json_string(&j, "input_hash", hash);
    cb_json_array(&j, "clips");
    for (uint32_t i = 0; i < h->clip_count; ++i) {
        cbpal_clip c;
        cbpal_get_clip(f, i, &c);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "name", c.name);
        cb_json_int(&j, "first_row", c.first_row);
        cb_json_int(&j, "frames", c.frames);
        cb_json_number(&j, "fps", c.fps);
        cb_json_number(&j, "duration", c.duration);
        cb_json_bool(&j, "loops", (c.flags & CBPAL_CLIP_LOOPS) != 0);
        cb_json_bool(&j, "fitted_rows", (c.flags & CBPAL_CLIP_FITTED) != 0);
        cb_json_inline_array(&j, "root_velocity");
        for (int k = 0; k < 3; ++k) cb_json_number(&j, NULL, c.root_velocity[k]);
        cb_json_end(&j);
        cb_json_end(&j);
    }
    cb_json_end(&j);
    cb_json_array(&j, "bones");
    for (uint32_t i = 0; i < h->bone_count; ++i) {
        cbpal_bone b;
        cbpal_get_bone(f, i, &b);
        cb_json_string(&j, NULL, b.name);
    }
    cb_json_end(&j);
    if (clip >= 0) {
        cbpal_clip c;
        cbpal_get_clip(f, (uint32_t)clip, &c);
        cb_json_string(&j, "clip", c.name);
        cb_json_int(&j, "frame", frame);
        cb_json_array(&j, "joints");
        for (uint32_t b = 0; b < h->bone_count; ++b) {
            double m[16];
            cb_palette_decode(view, f->texels, c.first_row + (uint32_t)frame, b, m);
            cb_json_inline_array(&j, NULL);
            for (int k = 0; k < 16; ++k) cb_json_number(&j, NULL, m[k]);
            cb_json_end(&j);
        }
        cb_json_end(&j);
    }
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

int cmd_inspect(int argc, char **argv)
{
    const char *path = NULL, *clip_name = NULL, *frame_text = NULL;
    bool json = false, no_verify = false, help;
    const cli_option options[] = {{"--json", NULL, NULL, &json},
                                  {"--clip", "NAME", &clip_name, NULL},
                                  {"--frame", "I", &frame_text, NULL},
                                  {"--no-verify", NULL, NULL, &no_verify}};
    int rc = cli_parse(argc, argv, options, 4, &path, 1, 1, &help);
    if (help) return fputs(cmd_inspect_usage, stdout), 0;
    if (rc) return rc;
    if (!clip_name != !frame_text) return cli_usage_error("inspect", "--clip and --frame go together");
    size_t n = strlen(path);
    if (n >= 4 && strcmp(path + n - 4, ".exr") == 0) return inspect_exr(path, json);
    char ktx2[1024];
    if (cli_file_kind_of(path) == CLI_FILE_KTX2)
        return fprintf(stderr, "crowdbake: %s\n", cli_ktx2_not_read(path, "inspect", ktx2, sizeof ktx2)), CLI_EXIT_USAGE;
    cbpal_file f;
    char msg[512];
    if (cbpal_open(path, no_verify ? 0 : CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg) != 0) {
        cb_error err = {0};
        cb_fail(&err, CB_ERR_INPUT, "%s", msg);
        return cli_report(&err);
    }
    int clip = -1;
    unsigned frame = 0;
    cb_error err = {0};
    if (clip_name) {
        const char **names = calloc(f.header.clip_count + 1, sizeof *names);
        cbpal_clip c;
        for (uint32_t i = 0; names && i < f.header.clip_count; ++i) cbpal_get_clip(&f, i, &c), names[i] = c.name;
        char why[512] = "out of memory";
        if (names) clip = cli_match_clip(clip_name, names, f.header.clip_count, sizeof *names, why, sizeof why);
        free(names);
        if (clip < 0) cb_fail(&err, CB_ERR_SETTINGS, "%s: --clip %s: %s", path, clip_name, why);
        else if (!cli_parse_u32(frame_text, &frame) || (cbpal_get_clip(&f, (uint32_t)clip, &c), frame >= c.frames))
            cb_fail(&err, CB_ERR_SETTINGS, "%s: clip '%s' has %u frames; --frame %s is not one of them", path, clip_name,
                    c.frames, frame_text);
    }
    if (!err.status) {
        cb_palette view;
        if (!cb_palette_view(&f, &view, &err)) {
            if (json || clip >= 0) print_pal_json(path, &f, &view, clip, (long)frame);
            else print_pal_text(path, &f);
            cb_palette_view_free(&view);
        }
    }
    cbpal_close(&f);
    return err.status ? cli_report(&err) : 0;
}
