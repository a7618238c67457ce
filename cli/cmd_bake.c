/* cmd_bake.c - `crowdbake bake MODEL -o OUT.pal|.exr|.ktx2|.bvat.json`: the main job. */
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "crowdbake/bake.h"
#include "crowdbake/budget.h"
#include "cli.h"
#include "internal/plumbing.h"
#include "internal/bake_words.h"

const char cmd_bake_usage[] =
    "usage: crowdbake bake MODEL -o OUT.pal|OUT.exr|OUT.ktx2|OUT.bvat.json [options]\n"
    "       crowdbake bake CATALOG.toml [-j N] [--force] [--depfile FILE] [--manifest FILE] [--out-dir DIR] [--json]\n"
    "                      [--type NAME [--fragment FILE]]\n"
    "                      [-q|-v] [--sync STATE=speed|time,...] [--default-state STATE]\n"
    "                      [--fps N|auto] [--max-error MM_PER_M] [--max-fps N] [--fit-rows] [--allow-over-budget]\n"
    "                      [--layout L] [--precision P] [--format F] [--zstd]\n"
    "                      [--max-texture-size N] [--row-travel auto|off] [--bone-space global|local]\n"
    "                      [--root-motion R] [--exr-compression C]\n\n"
    "Bakes every clip of the model's skin into a bone-matrix palette; or every animal type of a\n"
    "catalog (see catalog.example.toml) into palettes and a roster manifest, re-baking only what\n"
    "changed (--force: everything), N types at a time (default: the number of cores). With a\n"
    "catalog, the bake options given replace its [bake] and [animal] values for this run and count\n"
    "in what is up to date; a clip's own fps and max_error still apply (each setting: the catalog\n"
    "clip's, else the command line's, else the animal's, else [bake]'s, else the default);\n"
    "--depfile writes a Make/Ninja depfile;\n"
    "--out-dir replaces the catalog's out_dir (a path from the current directory);\n"
    "--type NAME bakes that animal type alone, as one build action of many (docs/bazel.md): its outputs\n"
    "and, in place of the manifest, a fragment of it (--fragment FILE, default OUT_DIR/NAME.fragment)\n"
    "that 'crowdbake roster merge' joins with the other types' into the manifest;\n"
    "--depfile-manifest-only writes the manifest's rule alone, as Ninja's depfile without\n"
    "deps = gcc (CMake's DEPFILE) wants it. --sync STATE=speed|time|auto (comma-separated) and\n"
    "--default-state STATE replace the catalog's word on those states in every animal that has\n"
    "them: whether a state follows the instance's speed, and the state a herd spawns in.\n\n"
    "  -o, --output FILE          .pal (mmap-ready, docs/pal-format.md), .exr (OpenEXR), .ktx2\n"
    "                             (uncompressed KTX2, RGBA16F/RGBA32F) or .bvat.json (Babylon.js's\n"
    "                             baked vertex animation data and clip table, docs/babylon.md);\n"
    "                             another extension is refused\n"
    "  --format F                 a comma-separated set of pal, exr, ktx2 and babylon (.bvat.json): write\n"
    "                             these formats (OUT's extension is replaced per format; each keeps\n"
    "                             its own default precision unless --precision is given; babylon is\n"
    "                             always float mat4)\n"
    "  --fps N|auto               baked frames per second; default auto: per clip, the fewest rows whose\n"
    "                             visible error (at the rows and between them, as the runtime blends\n"
    "                             them) stays within --max-error, fitted or sampled (ties: sampled),\n"
    "                             up to --max-fps; N: a fixed rate, rows sampled (--fps 30: the old\n"
    "                             default's bytes)\n"
    "  --max-error MM_PER_M       the error budget, mm per metre of model height; a clip over it fails\n"
    "                             the bake (exit 6, nothing written, a line per clip with what would\n"
    "                             meet it); with --fps N, a check of the fixed rate. Left out: 1, a\n"
    "                             goal, not a promise (a clip over it is written at the best the bake\n"
    "                             reached, with a warning saying what would meet it)\n"
    "  --max-fps N                the highest rate auto may choose (default 120: every clip of Cow,\n"
    "                             Fox and the samples meets 1 mm/m under it; a clip the default\n"
    "                             max_error is out of reach for under it goes on to 240, said per\n"
    "                             clip; given, it caps every clip)\n"
    "  --allow-over-budget        write a bake with clips over --max-error anyway, with a warning per\n"
    "                             clip (and \"over_budget\" in --json)\n"
    "  --layout mat4|affine|qpos  texels per bone: 4, 3 or 2 (default qpos; affine when the rig has\n"
    "                             non-uniform scale or shear, which qpos cannot hold)\n"
    "  --precision float|half|u16 RGBA32F, RGBA16F or RGBA16UI (default u16 for .pal, half for .ktx2,\n"
    "                             float for .exr; KTX2 and EXR refuse u16)\n"
    "  --fit-rows                 fit every clip's rows to the runtime's linear blend instead of\n"
    "                             sampling them: each row moves out by half the arc a bone cuts as a\n"
    "                             chord between rows, which halves that error (the encoding error at\n"
    "                             the rows grows to about the same size); no shader change (auto\n"
    "                             fits the clips it saves rows on without it)\n"
    "  --measure-all              measure the errors at every row and between every two, however\n"
    "                             many (default: past 1024 rows and 4M rows x skinned vertices, at\n"
    "                             an even subset of the rows, each clip's last always; faster on\n"
    "                             large rigs, but it can miss the one fast interval where the blend\n"
    "                             errs most)\n"
    "  --plant-feet               lock planted feet at bake time: in a locomotion loop whose feet slide\n"
    "                             over 10% of its ground speed, turn each leg's two bones (IK) so a\n"
    "                             planted foot stays where it landed; only the legs change, what\n"
    "                             changed is listed per clip (catalog: plant_feet = true)\n"
    "  --row-travel auto|off      per-row travel offsets (.pal version 5): auto ships them for the\n"
    "                             striding loops whose planted feet they keep still (slide cut by a\n"
    "                             third or more; info and the manifest say why per clip); off: none\n"
    "  --bone-space global|local  what a .pal row holds per bone: local (default) its transform in\n"
    "                             its parent's frame (.pal version 6), blended bone by bone and composed\n"
    "                             by the runtime (a bone pass, once per instance): the glTF's own\n"
    "                             interpolation, fewer rows for the same error; qpos, u16 or float,\n"
    "                             sampled rows only (else the default is global). global: each bone's\n"
    "                             skinning transform, for a vertex shader without a bone pass. Other\n"
    "                             formats beside the .pal are baked global (catalog: bone_space)\n"
    "  --timed-rows auto|on|off   an auto rate's rows on the clip's key times, a map saying which two\n"
    "                             rows each moment blends (.pal version 7). Local rows: auto (default)\n"
    "                             where that takes fewer bytes than one uniform rate, on wherever the\n"
    "                             keys allow, off never. Global rows: on where fewer bytes (auto, off:\n"
    "                             never; weighing them slows the bake) (catalog: timed_rows)\n"
    "  --max-texture-size N       never emit a dimension above N (default 16384); rows wrap into\n"
    "                             side-by-side column blocks\n"
    "  --root-motion keep|in-place|loops-in-place  in-place removes the root's average horizontal\n"
    "                             travel (the clip records it as a velocity), loops-in-place from the\n"
    "                             loops only; default: keep, or loops-in-place when a loop travels\n"
    "  --skin NAME|INDEX          the skin to bake when the file has several\n"
    "  --clip A,B                 only these clips, in this order (default: every clip; a clip that\n"
    "                             cannot be sampled, e.g. one without keys, is skipped with a warning\n"
    "                             unless named here, which makes it an error)\n"
    "  --exclude-clip A,B         every clip but these\n"
    "  --loop A,B                 these clips loop, --one-shot A,B these play once, whatever their\n"
    "  --one-shot A,B             poses say (default: decided from the poses; `info` says why)\n"
    "  --speed-reference UNITS_PER_S  ground speed at playback rate 1 (model units/s), stored in the header\n"
    "  --zstd                     compress the .pal payload (readers decompress once) and the .ktx2\n"
    "                             level (Zstandard supercompression, as toktx --zcmp)\n"
    "  --exr-compression none|rle|zips|zip|piz  (default none; lossless only)\n"
    "  -j, --threads N            sample clips on N threads (default: the number of cores); the\n"
    "                             output is byte-identical for any N\n"
    "  --json                     a machine-readable summary on stdout, warnings included\n"
    "  -q, --quiet                no summary lines, notes or progress (a bake's warnings still show)\n"
    "  -v, --verbose              each file read and written with its time; a catalog's progress\n";

typedef struct bake_args {
    const char *model, *output, *format, *fps, *layout, *precision, *max_size, *root_motion, *skin, *speed_ref,
        *exr_compression, *threads, *depfile, *manifest, *max_error, *max_fps, *clips, *excluded, *out_dir, *loops,
        *one_shots, *syncs, *default_state, *type, *fragment, *row_travel, *bone_space, *timed_rows;
    bool zstd, json, quiet, force, depfile_manifest, fit, measure_all, over_budget, plant_feet;
    cli_output out;
} bake_args;

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* OUT with its extension replaced by ext. */
static void output_path(const char *out, const char *ext, char *buf, size_t size)
{
    const char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
    size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - out) : strlen(out);
    snprintf(buf, size, "%.*s.%s", (int)stem, out, ext);
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcmp(s + n - k, suffix) == 0;
}

/* The bake options given, into the settings a catalog's keys also fill (bake.h); `fields`
 * says which were given (CB_BAKE_*). Only the command line's words are checked here: what a
 * setting means is the pipeline's. */
static int parse_settings(const bake_args *a, cb_bake_settings *s, unsigned *fields)
{
    *s = cb_default_bake_settings();
    *fields = 0;
    if (a->fps) s->from.fps = CB_FROM_COMMAND_LINE;
    if (a->fps && strcmp(a->fps, "auto") != 0) {
        s->fps_auto = false;
        if (!cli_parse_double(a->fps, &s->fps) || !cb_fps_valid(s->fps))
            return cli_usage_error("bake", "--fps wants auto or a number between 0 and 1000, got '%s'", a->fps);
        if (a->max_fps) return cli_usage_error("bake", "--max-fps caps the rates auto chooses; --fps %s is fixed", a->fps);
    }
    if (a->layout && !cb_layout_parse(a->layout, &s->layout))
        return cli_usage_error("bake", "--layout is mat4, affine or qpos, got '%s'", a->layout);
    if (a->precision && !cb_precision_parse(a->precision, &s->precision))
        return cli_usage_error("bake", "--precision is float, half or u16, got '%s'", a->precision);
    s->layout_set = a->layout != NULL, s->precision_set = a->precision != NULL;
    unsigned max;
    if (a->max_size) {
        if (!cli_parse_u32(a->max_size, &max) || max < 1)
            return cli_usage_error("bake", "--max-texture-size wants a positive integer");
        s->max_texture_size = max;
    }
    if (a->root_motion && !cb_root_motion_parse(a->root_motion, &s->root_motion))
        return cli_usage_error("bake", "--root-motion is keep, in-place or loops-in-place");
    if (a->root_motion) s->from.root_motion = CB_FROM_COMMAND_LINE;
    if (a->format && !(s->formats = cb_formats_parse(a->format)))
        return cli_usage_error("bake", "--format is pal, exr or pal,exr (any comma-separated set of pal, exr, ktx2 and babylon), "
                               "got '%s'", a->format);
    if (a->exr_compression && !cb_exr_compression_parse(a->exr_compression, &s->exr_compression))
        return cli_usage_error("bake", "--exr-compression is none, rle, zips, zip or piz (lossless only)");
    s->zstd = a->zstd;
    s->fit_rows = a->fit;
    if (a->fit) s->from.fit_rows = CB_FROM_COMMAND_LINE;
    s->measure_all = a->measure_all;
    s->plant_feet = a->plant_feet;
    if (a->row_travel && strcmp(a->row_travel, "off") != 0 && strcmp(a->row_travel, "auto") != 0)
        return cli_usage_error("bake", "--row-travel is auto or off, got '%s'", a->row_travel);
    s->row_travel_off = a->row_travel && strcmp(a->row_travel, "off") == 0;
    if (a->bone_space && !cb_bone_space_parse(a->bone_space, &s->bone_space))
        return cli_usage_error("bake", "--bone-space is global or local, got '%s'", a->bone_space);
    s->bone_space_set = a->bone_space != NULL;
    if (a->timed_rows && !cb_timed_rows_parse(a->timed_rows, &s->timed_rows))
        return cli_usage_error("bake", "--timed-rows is auto, on or off, got '%s'", a->timed_rows);
    s->allow_over_budget = a->over_budget;
    s->max_error_given = a->max_error != NULL;
    if (a->max_error && (!cli_parse_double(a->max_error, &s->max_error_mm) || !(s->max_error_mm > 0)))
        return cli_usage_error("bake", "--max-error wants mm per metre of model height");
    if (a->max_fps && (!cli_parse_double(a->max_fps, &s->max_fps) || !cb_max_fps_valid(s->max_fps)))
        return cli_usage_error("bake", "--max-fps wants 2..1000");
    if (a->max_error) s->from.max_error = CB_FROM_COMMAND_LINE;
    if (a->max_fps) s->from.max_fps = CB_FROM_COMMAND_LINE;
    *fields = (a->fps ? CB_BAKE_FPS : 0u) | (a->layout ? CB_BAKE_LAYOUT : 0u) | (a->precision ? CB_BAKE_PRECISION : 0u) |
              (a->max_size ? CB_BAKE_MAX_TEXTURE_SIZE : 0u) | (a->root_motion ? CB_BAKE_ROOT_MOTION : 0u) |
              (a->format ? CB_BAKE_FORMATS : 0u) | (a->zstd ? CB_BAKE_ZSTD : 0u) |
              (a->exr_compression ? CB_BAKE_EXR_COMPRESSION : 0u) | (a->fit ? CB_BAKE_FIT_ROWS : 0u) |
              (a->measure_all ? CB_BAKE_MEASURE_ALL : 0u) | (a->over_budget ? CB_BAKE_ALLOW_OVER_BUDGET : 0u) |
              (a->max_error ? CB_BAKE_MAX_ERROR : 0u) | (a->max_fps ? CB_BAKE_MAX_FPS : 0u) |
              (a->plant_feet ? CB_BAKE_PLANT_FEET : 0u) | (a->row_travel ? CB_BAKE_ROW_TRAVEL : 0u) |
              (a->bone_space ? CB_BAKE_BONE_SPACE : 0u) | (a->timed_rows ? CB_BAKE_TIMED_ROWS : 0u);
    return 0;
}

static int parse_threads(const char *text, unsigned *threads, const char *what)
{
    *threads = (unsigned)sysconf(_SC_NPROCESSORS_ONLN);
    if (text && (!cli_parse_u32(text, threads) || *threads < 1 || *threads > 64))
        return cli_usage_error("bake", "%s wants 1..64", what);
    return 0;
}

/* A catalog: the bake options given override its [bake] and [animal] settings for this run
 * (and count in what is up to date); options that only mean something for one model are
 * refused, never ignored. */
static int bake_catalog(const bake_args *a, const cb_limits *limits)
{
    unsigned jobs;
    if (parse_threads(a->threads, &jobs, "-j")) return CLI_EXIT_USAGE;
    if (a->output) return cli_usage_error("bake", "a catalog writes to its [bake] out_dir; -o is for single models");
    if (a->skin) return cli_usage_error("bake", "--skin is for single models (a catalog bakes each model's skinned mesh)");
    if (a->speed_ref) return cli_usage_error("bake", "--speed-reference is for single models; a catalog sets speed_reference per animal");
    if (a->clips || a->excluded)
        return cli_usage_error("bake", "--clip and --exclude-clip are for single models; a catalog lists clips per animal");
    if (a->loops || a->one_shots)
        return cli_usage_error("bake", "--loop and --one-shot are for single models; a catalog sets loop per clip");
    unsigned formats = a->format ? cb_formats_parse(a->format) : 0;
    if (a->format && !formats) return cli_usage_error("bake", "--format is pal, exr or pal,exr");
    if (formats && !cb_catalog_formats_valid(formats))
        return cli_usage_error("bake", "a catalog writes pal, exr or ktx2 (or several), and babylon beside any of them "
                               "(--format pal,babylon)");
    if (a->zstd && a->format && !(cb_formats_parse(a->format) & CB_FORMAT_PAL))
        return cli_usage_error("bake", "--zstd compresses .pal payloads (a catalog writes no .ktx2); EXR takes --exr-compression");
    cb_bake_settings over;
    unsigned fields;
    int rc = parse_settings(a, &over, &fields);
    if (rc) return rc;
    if (a->out_dir) over.out_dir = a->out_dir, fields |= CB_BAKE_OUT_DIR;
    if (a->depfile_manifest && !a->depfile) return cli_usage_error("bake", "--depfile-manifest-only goes with --depfile");
    if (a->fragment && !a->type) return cli_usage_error("bake", "--fragment goes with --type NAME");
    if (a->type && a->manifest)
        return cli_usage_error("bake", "--type writes a fragment (--fragment FILE), not a manifest: "
                               "'crowdbake roster merge' writes the manifest from every type's fragment");
    cli_catalog_bake cb = {a->model, jobs, a->force, a->quiet, a->json, a->depfile, a->manifest, a->type, a->fragment,
                           a->depfile_manifest, limits, &over, fields, a->syncs, a->default_state, &a->out};
    return cmd_bake_catalog(&cb);
}

/* Both sizes, as a catalog's log gives them: the texture as uploaded, and the file (its header
 * and tables too, or compressed). Both error figures: the encoding's at the baked rows, and what a
 * player sees (the runtime's blend of two rows, halfway between them), which is usually far larger. */
static void print_summary(const cb_bake_output *out, double seconds)
{
    const cb_palette *p = &out->palette;
    printf("%s: %.1f KiB texture, %.1f KiB file, %ux%u texels (%u block%s), %u bone%s, %u clip%s, %u row%s, %s/%s, encoding error %.3g mm/m "
           "(at the baked rows), visible error %.3g mm/m (blending rows at runtime), %.0f ms\n",
           out->path, p->texel_bytes / 1024.0, out->file_bytes / 1024.0, p->width, p->height, p->blocks, p->blocks == 1 ? "" : "s", p->bone_count,
           p->bone_count == 1 ? "" : "s", p->clip_count, p->clip_count == 1 ? "" : "s", p->rows, p->rows == 1 ? "" : "s",
           cb_layout_name(p->layout), cb_precision_name(p->precision), cb_mm_per_m(p->max_error, p->model_height),
           cb_mm_per_m(p->visible_error, p->model_height), seconds * 1000);
    if (p->error_rows_measured && p->error_rows_measured < p->rows) /* 0: nothing skinned, nothing measured */
        printf("  errors measured at %u of the %u rows, an even subset (the rig is past the measuring budget); "
               "--measure-all measures every row\n", p->error_rows_measured, p->rows);
}

static void json_output(cb_json *j, const cb_bake_settings *settings, const cb_bake_output *out, double seconds, double load)
{
    const cb_palette *p = &out->palette;
    cb_json_object(j, NULL);
    cb_json_string(j, "path", out->path);
    cb_json_string(j, "format", cb_output_format_of(out->format)->name);
    cb_json_int(j, "bytes", (long long)out->file_bytes);
    cb_json_int(j, "texture_bytes", (long long)p->texel_bytes); /* as uploaded: what a catalog's log and report give */
    cb_json_int(j, "width", p->width);
    cb_json_int(j, "height", p->height);
    cb_json_int(j, "blocks", p->blocks);
    cb_json_int(j, "bones", p->bone_count);
    cb_json_int(j, "clips", p->clip_count);
    cb_json_int(j, "rows", p->rows); /* every clip's baked frames, one texture row each */
    cb_json_string(j, "layout", cb_layout_name(p->layout));
    cb_json_string(j, "precision", cb_precision_name(p->precision));
    cb_json_bool(j, "fitted_rows", p->fitted);
    char why[600];
    cb_bake_bone_space_why(settings, out->format, p->bone_space, p->fallback_note, why, sizeof why);
    cb_json_string(j, "bone_space", cb_bone_space_name(p->bone_space));
    cb_json_string(j, "bone_space_why", why);
    cb_json_number(j, "max_error", p->max_error);
    cb_json_number(j, "model_height", p->model_height);
    cb_json_number(j, "max_error_mm_per_m", cb_mm_per_m(p->max_error, p->model_height));
    cb_json_number(j, "visible_error", p->visible_error);
    cb_json_number(j, "visible_error_mm_per_m", cb_mm_per_m(p->visible_error, p->model_height));
    cb_json_int(j, "error_rows_measured", p->error_rows_measured);
    cb_json_number(j, "seconds", seconds);
    cb_json_object(j, "phases");
    cb_json_number(j, "load", load);
    cb_json_number(j, "sample", p->seconds_sample);
    cb_json_number(j, "encode", p->seconds_encode);
    cb_json_number(j, "measure", p->seconds_measure);
    cb_json_number(j, "write", out->seconds_write);
    cb_json_end(j);
    cb_json_end(j);
}

static const char *clip_label(const cb_bake_job *job, uint32_t i)
{
    const cb_clip_plan *c = &job->plan[i];
    return c->name ? c->name : job->model->animations[c->animation].name;
}

/* The rows' bone space, a decision the bake takes for the user, and why (docs/usage.md, --bone-space). */
static void print_bone_space(const cb_bake_settings *s, const cb_bake_output *out)
{
    char why[600];
    cb_bake_bone_space_why(s, out->format, out->palette.bone_space, out->palette.fallback_note, why, sizeof why);
    printf("  %s\n", why);
}

/* The rows error-bounded rates took against a fixed 30 fps (the old default). */
static cb_status print_saving(const cb_bake_job *job, const cb_bake_result *r, cb_error *err)
{
    const cb_model *m = job->model;
    cb_sampler *s = cb_sampler_create(m, job->skin, err);
    if (!s) return err->status;
    const cb_palette *p = &r->outputs[0].palette;
    uint64_t rows_30 = 0;
    for (uint32_t i = 0; i < job->plan_count && !err->status; ++i) {
        uint32_t frames;
        if (!cb_bake_clip_frames_at(job, s, i, 30, &frames, err)) rows_30 += frames;
    }
    if (!err->status) {
        cb_texture_geometry g;
        uint64_t b_30 = cb_palette_texture_bytes(p->bone_count, (uint32_t)rows_30, p->layout, p->precision,
                                                 job->settings.max_texture_size, &g);
        printf("  %u rows, %.1f KiB, against %llu rows, %.1f KiB at a fixed 30 fps (%.2fx the bytes)\n", p->rows,
               p->texel_bytes / 1024.0, (unsigned long long)rows_30, b_30 / 1024.0, b_30 ? (double)p->texel_bytes / b_30 : 0);
        print_bone_space(&job->settings, &r->outputs[0]);
    }
    cb_sampler_free(s);
    return err->status;
}

/* Each clip's rate and rows, and why (error-bounded bakes). */
static void print_clips(const cb_bake_job *job, const cb_bake_result *r)
{
    int width = 0; /* the longest name: exporters prefix clips ("AnimalArmature|Walk") */
    for (uint32_t i = 0; i < r->budget_count; ++i)
        if ((int)strlen(clip_label(job, i)) > width) width = (int)strlen(clip_label(job, i));
    for (uint32_t i = 0; i < r->budget_count; ++i) {
        const cb_clip_budget *b = &r->budgets[i];
        char why[320];
        cb_bake_clip_reason(job, i, why, sizeof why);
        printf("  %-*s %4u rows, visible error %.3f mm/m%s: %s\n", width, clip_label(job, i), b->rows, b->error_mm,
               b->over ? " (OVER max_error)" : "", why);
    }
}

static bool any_auto(const cb_bake_job *job)
{
    for (uint32_t i = 0; i < job->plan_count; ++i)
        if (cb_bake_job_clip_auto(job, i)) return true;
    return false;
}

/* Clips over their budget: a line each, on stderr when the bake failed for them (a budget the
 * user stated), else as warnings (written: over the default budget, a goal, or
 * --allow-over-budget). */
static void report_over_budget(const cb_bake_job *job, const cb_bake_result *r, cb_warnings *warnings)
{
    for (uint32_t i = 0; i < r->budget_count; ++i) {
        if (!r->budgets[i].over || (!warnings && r->budgets[i].goal)) continue;
        char text[640], why[160];
        cb_bake_budget_text(job, r, i, cli_setting_flag, text, sizeof text);
        cb_bake_goal_words(&r->budgets[i], cli_setting_flag, job->settings.allow_over_budget, why, sizeof why);
        if (warnings) cb_warn(warnings, "warning", "%s%s", text, why);
        else fprintf(stderr, "crowdbake: %s: %s\n", job->model->source, text);
    }
}

static void json_clips(cb_json *j, const cb_bake_job *job, const cb_bake_result *r)
{
    cb_json_array(j, "clips");
    for (uint32_t i = 0; i < r->budget_count; ++i) {
        const cb_clip_budget *b = &r->budgets[i];
        char why[320], settings[400];
        cb_bake_clip_reason(job, i, why, sizeof why);
        cb_clip_settings_text(&job->clip_settings[i], settings, sizeof settings);
        cb_json_object(j, NULL);
        cb_json_string(j, "name", clip_label(job, i));
        cb_json_number(j, "fps", b->fps);
        cb_json_int(j, "rows", b->rows);
        cb_json_bool(j, "fitted_rows", b->fitted);
        cb_json_bool(j, "error_bounded", cb_bake_job_clip_auto(job, i));
        cb_json_number(j, "visible_error_mm_per_m", b->error_mm);
        cb_json_number(j, "max_error_mm_per_m", b->max_error_mm);
        cb_json_string(j, "why", why);
        if (job->plan[i].timed_rows) { /* rows on its keys: fps is its map's cell rate (absent: uniform rows) */
            cb_json_int(j, "timed_rows", job->plan[i].timed_rows);
            cb_json_int(j, "map_rows", job->rates[i].timed_map_rows);
            cb_json_int(j, "cells", job->rates[i].timed_cells);
        }
        cb_json_string(j, "settings", settings);
        cb_json_end(j);
    }
    cb_json_end(j);
    cb_json_array(j, "over_budget"); /* written: over the default budget or --allow-over-budget; else the bake failed */
    for (uint32_t i = 0; i < r->budget_count; ++i) {
        if (!r->budgets[i].over) continue;
        char text[640];
        cb_bake_budget_text(job, r, i, cli_setting_flag, text, sizeof text);
        cb_json_object(j, NULL);
        cb_json_string(j, "name", clip_label(job, i));
        cb_json_number(j, "visible_error_mm_per_m", r->budgets[i].error_mm);
        cb_json_number(j, "max_error_mm_per_m", r->budgets[i].max_error_mm);
        cb_json_number(j, "fps_needed", job->rates[i].fps_needed);
        cb_json_bool(j, "default_budget", r->budgets[i].goal); /* a goal: written at the best the bake reached */
        cb_json_string(j, "message", text);
        cb_json_end(j);
    }
    cb_json_end(j);
}

/* The extensions of the table of formats, for messages: "OUT.pal, OUT.exr, OUT.ktx2 or OUT.bvat.json". */
static void extensions_text(char *buf, size_t size)
{
    buf[0] = '\0';
    uint32_t n = cb_output_format_count();
    for (uint32_t i = 0; i < n; ++i)
        snprintf(buf + strlen(buf), size - strlen(buf), "%sOUT%s", i == 0 ? "" : i + 1 == n ? " or " : ", ",
                 cb_output_format_at(i)->extension);
}

/* --format, or OUT's extension (the table of formats): none (a device, a pipe) is a .pal, as
 * always; another extension is refused, never guessed. */
static int output_formats(const bake_args *a, unsigned *formats)
{
    if (a->format) return 0; /* parse_settings read it */
    const char *dot = strrchr(a->output, '.'), *slash = strrchr(a->output, '/');
    const char *ext = dot && (!slash || dot > slash) ? dot : "";
    const cb_output_format *f = cb_output_format_for_path(a->output);
    *formats = f ? f->format : !ext[0] ? CB_FORMAT_PAL : 0;
    char known[256];
    extensions_text(known, sizeof known);
    if (!*formats)
        return cli_usage_error("bake", "%s: unknown output extension '%s'; write %s, or give --format pal,exr", a->output,
                               ext, known);
    return 0;
}

/* Each format's path: OUT itself for the format it names (or for the one format asked for),
 * else OUT with that format's extension (--format pal,exr -o fox: fox.pal and fox.exr). */
static uint32_t output_paths(const bake_args *a, unsigned formats, char (*buf)[4096], cb_output_path *outs)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < cb_output_format_count(); ++i) {
        const cb_output_format *f = cb_output_format_at(i);
        if (!(formats & f->format)) continue;
        if (!a->format || ends_with(a->output, f->extension)) snprintf(buf[n], sizeof buf[n], "%s", a->output);
        else output_path(a->output, f->extension + 1, buf[n], sizeof buf[n]);
        outs[n] = (cb_output_path){f->format, buf[n]};
        ++n;
    }
    return n;
}

/* Everything the command line decides before the job runs. */
static int single_model_checks(const bake_args *a, cb_bake_settings *s)
{
    int rc;
    if ((rc = output_formats(a, &s->formats))) return rc;
    bool want_pal = s->formats & CB_FORMAT_PAL;
    /* KTX2 could hold u16 as RGBA16UI, but three.js's KTX2Loader and most loaders refuse integer formats. */
    if (!cb_bake_settings_writable(s) && (s->formats & CB_FORMAT_EXR))
        return cli_usage_error("bake", "EXR holds half or float texels; use --precision half|float%s",
                               want_pal ? " (or write only the .pal)" : "");
    if (!cb_bake_settings_writable(s) && (s->formats & CB_FORMAT_BABYLON))
        return cli_usage_error("bake", "Babylon.js's baked vertex animation data is Float32 matrices, never u16; leave "
                               "--precision out (or write a .pal beside it, --format pal,babylon: u16 is then the .pal's)");
    if (!cb_bake_settings_writable(s))
        return cli_usage_error("bake", "KTX2 palettes hold half or float texels (RGBA16F, RGBA32F; common KTX2 loaders "
                               "refuse u16's RGBA16UI); use --precision half|float%s", want_pal ? " (or write only the .pal)" : "");
    if (a->zstd && !(s->formats & (CB_FORMAT_PAL | CB_FORMAT_KTX2)))
        return cli_usage_error("bake", "--zstd compresses .pal payloads and .ktx2 levels; EXR takes --exr-compression");
    return 0;
}

/* The bake line or --json, and the warnings: the model's, the bake's notes, clips written over
 * their budget. Error-bounded bakes list each clip's rate, rows and why. */
static void report_bake(const bake_args *a, const cb_bake_job *job, const cb_bake_result *r, double t0, double load)
{
    cb_warnings warnings = {0};
    cb_model_warnings(job->model, a->clips == NULL, &warnings);
    for (uint32_t i = 0; i < r->notes.count; ++i) cb_warn(&warnings, r->notes.items[i].kind, "%s", r->notes.items[i].message);
    if (job->speed_reference_from[0] && job->speed_reference > 0 && !a->json) /* --json: its own fields */
        cb_warn(&warnings, "note", "speed reference %.4g units/s recorded: %s", job->speed_reference, job->speed_reference_from);
    report_over_budget(job, r, &warnings);
    double seconds = now_seconds() - t0;
    for (uint32_t i = 0; i < r->output_count; ++i)
        cli_verbose(&a->out, "wrote %s (%llu bytes; %s/%s, %u rows) in %.3f s", r->outputs[i].path,
                    (unsigned long long)r->outputs[i].file_bytes, cb_layout_name(r->outputs[i].palette.layout),
                    cb_precision_name(r->outputs[i].palette.precision), r->outputs[i].palette.rows, r->outputs[i].seconds_write);
    if (a->json) {
        cb_json j;
        cb_json_init(&j, stdout);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "model", a->model);
        cb_json_number(&j, "speed_reference", job->speed_reference);
        cb_json_string(&j, "speed_reference_from", a->speed_ref ? "the command line" : job->speed_reference_from);
        cb_json_array(&j, "outputs");
        for (uint32_t i = 0; i < r->output_count; ++i) json_output(&j, &job->settings, &r->outputs[i], seconds, load);
        cb_json_end(&j);
        json_clips(&j, job, r);
        cli_plant_json(&j, job);
        cli_json_warnings(&j, &warnings);
        cb_json_end(&j);
    } else {
        cb_error ignored = {0};
        if (!a->quiet && any_auto(job)) print_clips(job, r), print_saving(job, r, &ignored);
        if (!a->quiet) cli_plant_print(job);
        for (uint32_t i = 0; i < r->output_count && !a->quiet; ++i) print_summary(&r->outputs[i], seconds);
        cli_print_warnings(&warnings, !a->quiet);
    }
    cb_warnings_free(&warnings);
}

int cmd_bake(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    bake_args a = {0};
    if (cli_take_output(&argc, argv, &a.out)) return CLI_EXIT_USAGE;
    bool help;
    const cli_option options[] = {
        {"-o", "FILE", &a.output, NULL},           {"--output", "FILE", &a.output, NULL},
        {"--format", "pal,exr", &a.format, NULL},  {"--fps", "N", &a.fps, NULL},
        {"--layout", "LAYOUT", &a.layout, NULL},   {"--precision", "PRECISION", &a.precision, NULL},
        {"--max-texture-size", "N", &a.max_size, NULL}, {"--root-motion", "keep|in-place|loops-in-place", &a.root_motion, NULL},
        {"--skin", "NAME|INDEX", &a.skin, NULL},   {"--speed-reference", "UNITS_PER_S", &a.speed_ref, NULL},
        {"--exr-compression", "NAME", &a.exr_compression, NULL}, {"--zstd", NULL, NULL, &a.zstd},
        {"--json", NULL, NULL, &a.json},
        {"-j", "N", &a.threads, NULL},             {"--threads", "N", &a.threads, NULL},
        {"--force", NULL, NULL, &a.force},         {"--depfile", "FILE", &a.depfile, NULL},
        {"--manifest", "FILE", &a.manifest, NULL}, {"--max-error", "MM_PER_M", &a.max_error, NULL},
        {"--max-fps", "N", &a.max_fps, NULL},      {"--clip", "A,B", &a.clips, NULL},
        {"--exclude-clip", "A,B", &a.excluded, NULL}, {"--out-dir", "DIR", &a.out_dir, NULL},
        {"--loop", "A,B", &a.loops, NULL},         {"--one-shot", "A,B", &a.one_shots, NULL},
        {"--depfile-manifest-only", NULL, NULL, &a.depfile_manifest}, {"--fit-rows", NULL, NULL, &a.fit},
        {"--measure-all", NULL, NULL, &a.measure_all}, {"--plant-feet", NULL, NULL, &a.plant_feet},
        {"--measure-all", NULL, NULL, &a.measure_all}, {"--row-travel", "auto|off", &a.row_travel, NULL},
        {"--bone-space", "global|local", &a.bone_space, NULL}, {"--timed-rows", "auto|on|off", &a.timed_rows, NULL},
        {"--allow-over-budget", NULL, NULL, &a.over_budget},
        {"--type", "NAME", &a.type, NULL},        {"--fragment", "FILE", &a.fragment, NULL},
        {"--sync", "STATE=speed|time", &a.syncs, NULL}, {"--default-state", "STATE", &a.default_state, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &a.model, 1, 1, &help);
    if (help) return fputs(cmd_bake_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    a.quiet = a.out.quiet;
    if (ends_with(a.model, ".toml")) return bake_catalog(&a, &limits);
    if (!a.output) return cli_usage_error("bake", "-o OUT.pal, OUT.exr, OUT.ktx2 or OUT.bvat.json is required");
    if (a.depfile || a.depfile_manifest || a.manifest || a.force || a.out_dir || a.type || a.fragment)
        return cli_usage_error("bake", "%s is for catalogs (a single bake always writes its outputs)",
                               a.depfile ? "--depfile" : a.depfile_manifest ? "--depfile-manifest-only" : a.manifest
                               ? "--manifest" : a.force ? "--force" : a.out_dir ? "--out-dir" : a.type ? "--type"
                               : "--fragment");
    if (a.syncs || a.default_state)
        return cli_usage_error("bake", "%s is for catalogs: a single model has clips, not states",
                               a.syncs ? "--sync" : "--default-state");
    cb_bake_settings settings;
    unsigned fields, threads;
    if ((rc = parse_settings(&a, &settings, &fields)) || (rc = single_model_checks(&a, &settings))) return rc;
    double speed_ref = CB_SPEED_REFERENCE_AUTO; /* the job decides it (locomotion.h) */
    if (a.speed_ref && (!cli_parse_double(a.speed_ref, &speed_ref) || speed_ref < 0))
        return cli_usage_error("bake", "--speed-reference wants a non-negative speed in the model's units per second");
    if (parse_threads(a.threads, &threads, "--threads")) return CLI_EXIT_USAGE;

    double t0 = now_seconds();
    cb_error err = {0};
    cb_model *m = cli_load_model(&a.out, a.model, &limits, &err);
    if (!m) return cli_report(&err);
    double load = now_seconds() - t0;
    char paths[CB_OUTPUT_MAX][4096];
    cb_output_path outputs[CB_OUTPUT_MAX];
    uint32_t output_count = output_paths(&a, settings.formats, paths, outputs);
    cb_bake_job job;
    cb_bake_job_init(&job);
    job.model = m, job.skin = cli_pick_skin(m, a.skin, &err);
    job.settings = settings, job.limits = limits, job.threads = threads, job.speed_reference = speed_ref;
    job.outputs = outputs, job.output_count = output_count;
    cb_clip_plan *selection = NULL;
    cb_bake_result result = {0};
    if (job.skin >= 0 && !cli_select_clips(m, a.clips, a.excluded, &selection, &job.clip_count, &err) &&
        !cli_override_loops(m, a.loops, a.one_shots, &selection, &job.clip_count, &err)) {
        job.clips = selection;
        cb_bake_job_run(&job, &result, &err);
    }
    if (!err.status) report_bake(&a, &job, &result, t0, load);
    else if (result.over_budget) report_over_budget(&job, &result, NULL); /* a line each, above the error's */
    cb_bake_result_free(&result);
    cb_bake_job_free(&job);
    free(selection);
    cb_model_free(m);
    return err.status ? cli_report(&err) : 0;
}
