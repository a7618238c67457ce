/* cmd_bake.c - `crowdbake bake MODEL -o OUT.pal|OUT.exr`: the main job. */
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../formats/crowdbake_pal.h"
#include "../formats/exr_io.h"
#include "../formats/json_writer.h"
#include "../formats/ktx2_write.h"
#include "../formats/pal_write.h"
#include "../src/budget.h"
#include "../src/runtime.h"
#include "cli.h"

const char cmd_bake_usage[] =
    "usage: crowdbake bake MODEL -o OUT.pal|OUT.exr|OUT.ktx2 [options]\n"
    "       crowdbake bake CATALOG.toml [-j N] [--force] [--depfile FILE] [--manifest FILE] [--json] [-q]\n"
    "                      [--fps N] [--layout L] [--precision P] [--format F] [--zstd] [--max-texture-size N]\n"
    "                      [--root-motion R] [--exr-compression C]\n\n"
    "Bakes every clip of the model's skin into a bone-matrix palette; or every animal type of a\n"
    "catalog (see catalog.example.toml) into palettes and a roster manifest, re-baking only what\n"
    "changed (--force: everything), N types at a time (default: the number of cores). With a\n"
    "catalog, the bake options given replace its [bake] and [animal] values for this run (a clip's\n"
    "own fps still applies) and count in what is up to date; --depfile writes a Make/Ninja depfile.\n\n"
    "  -o, --output FILE          .pal (mmap-ready, docs/pal-format.md), .exr (OpenEXR) or .ktx2\n"
    "                             (uncompressed KTX2, RGBA16F/RGBA32F); another extension is refused\n"
    "  --format pal,exr,ktx2      write these formats (OUT's extension is replaced per format; each\n"
    "                             keeps its own default precision unless --precision is given)\n"
    "  --fps N|auto               baked frames per second (default 30); auto: per clip, the lowest rate\n"
    "                             whose error stays under --max-error (mm per metre of model height,\n"
    "                             default 1) at baked frames and between them, up to --max-fps (60)\n"
    "  --layout mat4|affine|qpos  texels per bone: 4, 3 or 2 (default qpos; affine when the rig has\n"
    "                             non-uniform scale or shear, which qpos cannot hold)\n"
    "  --precision float|half|u16 RGBA32F, RGBA16F or RGBA16UI (default u16 for .pal, float for .exr\n"
    "                             and .ktx2, which refuse u16)\n"
    "  --fit-rows                 fit the rows to the runtime's linear blend instead of sampling\n"
    "                             them: each row moves out by half the arc a bone cuts as a chord\n"
    "                             between rows, which halves that error (the encoding error at the\n"
    "                             rows grows to about the same size); no shader change\n"
    "  --max-texture-size N       never emit a dimension above N (default 16384); rows wrap into\n"
    "                             side-by-side column blocks\n"
    "  --root-motion keep|in-place  in-place removes the root's average horizontal travel\n"
    "  --skin NAME|INDEX          the skin to bake when the file has several\n"
    "  --clip A,B                 only these clips, in this order (default: every clip; a clip that\n"
    "                             cannot be sampled, e.g. one without keys, is skipped with a warning\n"
    "                             unless named here, which makes it an error)\n"
    "  --exclude-clip A,B         every clip but these\n"
    "  --speed-reference M_PER_S  ground speed at playback rate 1, stored in the header\n"
    "  --zstd                     compress the .pal payload (readers decompress once)\n"
    "  --exr-compression none|rle|zips|zip|piz  (default none; lossless only)\n"
    "  -j, --threads N            sample clips on N threads (default: the number of cores); the\n"
    "                             output is byte-identical for any N\n"
    "  --json                     a machine-readable summary on stdout, warnings included\n"
    "  -q, --quiet                no summary lines\n";

typedef struct bake_args {
    const char *model, *output, *format, *fps, *layout, *precision, *max_size, *root_motion, *skin, *speed_ref,
        *exr_compression, *threads, *depfile, *manifest, *max_error, *max_fps, *clips, *excluded;
    bool zstd, json, quiet, quiet_long, force, fit;
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

/* XXH64 of the crowdbake version, the options that shape the output, and the model's source bytes. */
static uint64_t input_hash(const cb_model *m, const cb_bake_options *o, int skin, bool zstd, int exr_compression)
{
    cbpal_xxh64_state s;
    cbpal_xxh64_init(&s);
    char opts[256];
    int n = snprintf(opts, sizeof opts, "crowdbake %s fps=%.17g layout=%s precision=%s max=%u root=%d skin=%d zstd=%d exr=%d%s\n",
                     CROWDBAKE_VERSION, o->fps, cb_layout_name(o->layout), cb_precision_name(o->precision),
                     o->max_texture_size, (int)o->root_motion, skin, zstd, exr_compression,
                     o->fit ? " fit-rows" : "");
    cbpal_xxh64_update(&s, opts, (size_t)n);
    cbpal_xxh64_update(&s, &m->source_hash, sizeof m->source_hash);
    return cbpal_xxh64_digest(&s);
}

/* The options of the .pal bake; *exr_precision: the .exr's texels (each format keeps its own
 * default precision when --precision is not given, so --format pal,exr changes neither file). */
static int parse_options(const bake_args *a, cb_bake_options *o, bool want_exr, bool want_ktx2, bool want_pal,
                         cb_precision *exr_precision)
{
    *o = cb_default_bake_options();
    if (a->fps && strcmp(a->fps, "auto") != 0 && (!cli_parse_double(a->fps, &o->fps) || !(o->fps > 0) || o->fps > 1000))
        return cli_usage_error("bake", "--fps wants a number between 0 and 1000, got '%s'", a->fps);
    if (a->layout && !cb_layout_parse(a->layout, &o->layout))
        return cli_usage_error("bake", "--layout is mat4, affine or qpos, got '%s'", a->layout);
    if (a->precision && !cb_precision_parse(a->precision, &o->precision))
        return cli_usage_error("bake", "--precision is float, half or u16, got '%s'", a->precision);
    o->fit = a->fit;
    /* EXR holds half or float; half misses 0.5 mm/m on the samples, so float unless asked. */
    *exr_precision = a->precision ? o->precision : CB_PRECISION_FLOAT;
    if (!want_pal) o->precision = *exr_precision;
    if (*exr_precision == CB_PRECISION_U16 && want_exr)
        return cli_usage_error("bake", "EXR holds half or float texels; use --precision half|float%s",
                               want_pal ? " (or write only the .pal)" : "");
    /* KTX2 could hold u16 as RGBA16UI, but three.js's KTX2Loader and most loaders refuse integer formats. */
    if (*exr_precision == CB_PRECISION_U16 && want_ktx2)
        return cli_usage_error("bake", "KTX2 palettes hold half or float texels (RGBA16F, RGBA32F; common KTX2 loaders "
                               "refuse u16's RGBA16UI); use --precision half|float%s", want_pal ? " (or write only the .pal)" : "");
    unsigned max;
    if (a->max_size) {
        if (!cli_parse_u32(a->max_size, &max) || max < 1)
            return cli_usage_error("bake", "--max-texture-size wants a positive integer");
        o->max_texture_size = max;
    }
    o->threads = (uint32_t)sysconf(_SC_NPROCESSORS_ONLN);
    if (a->threads && (!cli_parse_u32(a->threads, &o->threads) || o->threads < 1 || o->threads > 64))
        return cli_usage_error("bake", "--threads wants 1..64");
    if (a->root_motion) {
        if (strcmp(a->root_motion, "in-place") == 0) o->root_motion = CB_ROOT_MOTION_IN_PLACE;
        else if (strcmp(a->root_motion, "keep") != 0) return cli_usage_error("bake", "--root-motion is keep or in-place");
    }
    return 0;
}

/* --format's words: a comma-separated set of pal, exr and ktx2. */
static bool parse_formats(const char *text, bool *pal, bool *exr, bool *ktx2)
{
    *pal = *exr = *ktx2 = false;
    char buf[64];
    if (strlen(text) >= sizeof buf) return false;
    snprintf(buf, sizeof buf, "%s", text);
    for (char *save = NULL, *w = strtok_r(buf, ",", &save); w; w = strtok_r(NULL, ",", &save)) {
        bool *flag = strcmp(w, "pal") == 0 ? pal : strcmp(w, "exr") == 0 ? exr : strcmp(w, "ktx2") == 0 ? ktx2 : NULL;
        if (!flag || *flag) return false;
        *flag = true;
    }
    return *pal || *exr || *ktx2;
}

/* A catalog: the bake options given override its [bake] and [animal] settings for this run
 * (and count in what is up to date); options that only mean something for one model are
 * refused, never ignored. */
static int bake_catalog(const bake_args *a, const cb_limits *limits)
{
    unsigned jobs = (unsigned)sysconf(_SC_NPROCESSORS_ONLN);
    if (a->threads && (!cli_parse_u32(a->threads, &jobs) || jobs < 1 || jobs > 64))
        return cli_usage_error("bake", "-j wants 1..64");
    if (a->output) return cli_usage_error("bake", "a catalog writes to its [bake] out_dir; -o is for single models");
    if (a->skin) return cli_usage_error("bake", "--skin is for single models (a catalog bakes each model's skinned mesh)");
    if (a->speed_ref) return cli_usage_error("bake", "--speed-reference is for single models; a catalog sets speed_reference per animal");
    if (a->clips || a->excluded)
        return cli_usage_error("bake", "--clip and --exclude-clip are for single models; a catalog lists clips per animal");
    if ((a->fps && strcmp(a->fps, "auto") == 0) || a->max_error || a->max_fps)
        return cli_usage_error("bake", "--fps auto, --max-error and --max-fps are for single models; a catalog sets fps per "
                               "animal or clip");
    cb_bake_settings over = {0};
    unsigned fields = 0;
    bool pal = false, exr = false, ktx2 = false;
    if (a->format && !parse_formats(a->format, &pal, &exr, &ktx2)) return cli_usage_error("bake", "--format is pal, exr or pal,exr");
    if (ktx2) return cli_usage_error("bake", "--format ktx2 is for single models for now; a catalog writes pal and exr");
    if (a->format) over.formats = (pal ? CB_FORMAT_PAL : 0u) | (exr ? CB_FORMAT_EXR : 0u), fields |= CB_BAKE_FORMATS;
    if (a->zstd && a->format && !pal)
        return cli_usage_error("bake", "--zstd compresses .pal payloads; EXR takes --exr-compression");
    if (a->zstd) over.zstd = true, fields |= CB_BAKE_ZSTD;
    if (a->exr_compression && !cb_exr_compression_parse(a->exr_compression, &over.exr_compression))
        return cli_usage_error("bake", "--exr-compression is none, rle, zips, zip or piz (lossless only)");
    if (a->exr_compression) fields |= CB_BAKE_EXR_COMPRESSION;
    cb_bake_options o;
    cb_precision exr_precision; /* the catalog's own rules pick each format's precision */
    int rc = parse_options(a, &o, false, false, true, &exr_precision); /* the same checks and values as for one model */
    if (rc) return rc;
    over.fps = o.fps, over.layout = o.layout, over.precision = o.precision;
    over.max_texture_size = o.max_texture_size, over.root_motion = o.root_motion, over.fit_rows = o.fit;
    fields |= (a->fps ? CB_BAKE_FPS : 0u) | (a->layout ? CB_BAKE_LAYOUT : 0u) | (a->precision ? CB_BAKE_PRECISION : 0u) |
              (a->max_size ? CB_BAKE_MAX_TEXTURE_SIZE : 0u) | (a->root_motion ? CB_BAKE_ROOT_MOTION : 0u) |
              (a->fit ? CB_BAKE_FIT_ROWS : 0u);
    cli_catalog_bake cb = {a->model, jobs, a->force, a->quiet, a->json, a->depfile, a->manifest, limits, &over, fields};
    return cmd_bake_catalog(&cb);
}


/* Both error figures: the encoding's at the baked rows, and what a player sees (the runtime's
 * blend of two rows, halfway between them), which is usually far larger. */
static void print_summary(const char *path, size_t bytes, const cb_palette *p, double seconds)
{
    printf("%s: %.1f KiB, %ux%u texels (%u block%s), %u bone%s, %u clip%s, %u frame%s, %s/%s, encoding error %.3g mm/m "
           "(at the baked rows), visible error %.3g mm/m (blending rows at runtime), %.0f ms\n",
           path, bytes / 1024.0, p->width, p->height, p->blocks, p->blocks == 1 ? "" : "s", p->bone_count,
           p->bone_count == 1 ? "" : "s", p->clip_count, p->clip_count == 1 ? "" : "s", p->rows, p->rows == 1 ? "" : "s",
           cb_layout_name(p->layout), cb_precision_name(p->precision), cb_mm_per_m(p->max_error, p->model_height),
           cb_mm_per_m(p->visible_error, p->model_height), seconds * 1000);
}

typedef struct phase_times {
    double load, write;
} phase_times;

static void json_output(cb_json *j, const char *path, const char *format, size_t bytes, const cb_palette *p, double seconds,
                        const phase_times *pt)
{
    cb_json_object(j, NULL);
    cb_json_string(j, "path", path);
    cb_json_string(j, "format", format);
    cb_json_int(j, "bytes", (long long)bytes);
    cb_json_int(j, "width", p->width);
    cb_json_int(j, "height", p->height);
    cb_json_int(j, "blocks", p->blocks);
    cb_json_int(j, "bones", p->bone_count);
    cb_json_int(j, "clips", p->clip_count);
    cb_json_int(j, "frames", p->rows);
    cb_json_string(j, "layout", cb_layout_name(p->layout));
    cb_json_string(j, "precision", cb_precision_name(p->precision));
    cb_json_bool(j, "fitted_rows", p->fitted);
    cb_json_number(j, "max_error", p->max_error);
    cb_json_number(j, "model_height", p->model_height);
    cb_json_number(j, "max_error_mm_per_m", cb_mm_per_m(p->max_error, p->model_height));
    cb_json_number(j, "visible_error", p->visible_error);
    cb_json_number(j, "visible_error_mm_per_m", cb_mm_per_m(p->visible_error, p->model_height));
    cb_json_int(j, "error_rows_measured", p->error_rows_measured);
    cb_json_number(j, "seconds", seconds);
    cb_json_object(j, "phases");
    cb_json_number(j, "load", pt->load);
    cb_json_number(j, "sample", p->seconds_sample);
    cb_json_number(j, "encode", p->seconds_encode);
    cb_json_number(j, "measure", p->seconds_measure);
    cb_json_number(j, "write", pt->write);
    cb_json_end(j);
    cb_json_end(j);
}

/* --fps auto: a rate per clip, chosen by measured error; prints what it chose and saved. */
static cb_clip_plan *choose_rates(cb_sampler *s, const cb_bake_options *o, const cb_clip_plan *selection,
                                  uint32_t selected, double max_mm, double max_fps, bool quiet, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    uint32_t n = selection ? selected : m->animation_count;
    cb_clip_plan *plan = calloc(n ? n : 1, sizeof *plan);
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    cb_rate_choice *chosen = calloc(n ? n : 1, sizeof *chosen);
    if (!plan || !goals || !chosen) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t i = 0; i < n && !err->status; ++i) {
        plan[i] = (cb_clip_plan){selection ? selection[i].animation : (int32_t)i, NULL, -1, 0};
        goals[i] = (cb_rate_goal){max_mm, max_fps};
    }
    uint64_t rows_auto = 0, rows_30 = 0;
    if (!err->status) cb_choose_rates(s, o, plan, n, goals, chosen, err);
    for (uint32_t i = 0; i < n && !err->status; ++i) {
        int32_t a = plan[i].animation;
        cb_clip_info at, fixed;
        if (cb_clip_analyze(s, a, plan[i].fps, -1, &o->limits, &at, err) ||
            cb_clip_analyze(s, a, 30, -1, &o->limits, &fixed, err))
            break;
        rows_auto += at.frames, rows_30 += fixed.frames;
        if (!quiet)
            printf("  %-24s %3.0f fps: %4u rows, visible error %.3f mm/m%s\n", m->animations[a].name, plan[i].fps, at.frames,
                   chosen[i].error_mm, chosen[i].met ? "" : " (over --max-error even at --max-fps)");
    }
    if (!err->status && !quiet) {
        cb_texture_geometry g;
        uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count;
        uint64_t b_auto = cb_palette_texture_bytes(bones, (uint32_t)rows_auto, o->layout, o->precision, o->max_texture_size, &g);
        uint64_t b_30 = cb_palette_texture_bytes(bones, (uint32_t)rows_30, o->layout, o->precision, o->max_texture_size, &g);
        printf("  auto fps: %llu rows, %.1f KiB, against %llu rows, %.1f KiB at 30 fps (%.0f%% %s)\n",
               (unsigned long long)rows_auto, b_auto / 1024.0, (unsigned long long)rows_30, b_30 / 1024.0,
               b_30 ? fabs(100.0 * (1 - (double)b_auto / b_30)) : 0, b_auto <= b_30 ? "saved" : "more");
    }
    free(goals), free(chosen);
    if (err->status) free(plan), plan = NULL;
    return plan;
}

/* Bakes the selected clips (NULL: every clip), with --fps auto choosing the rates first. */
static cb_status bake_palette(cb_sampler *s, cb_bake_options *o, const bake_args *a, const cb_clip_plan *selection,
                              uint32_t selected, double max_mm, double max_fps, bool quiet, cb_palette *p, cb_error *err)
{
    bool automatic = a->fps && strcmp(a->fps, "auto") == 0;
    o->affine_fallback = a->layout == NULL;
    cb_clip_plan *plan = automatic ? choose_rates(s, o, selection, selected, max_mm, max_fps, quiet, err) : NULL;
    uint32_t n = plan || selection ? (selection ? selected : cb_sampler_model(s)->animation_count) : 0;
    cb_status rc = err->status ? err->status : cb_palette_bake(s, o, plan ? plan : selection, n, p, err);
    free(plan);
    return rc;
}

/* What the user should know about a bake: clips skipped at load, ignored channels, the
 * layout's fallback, loops that travel, quaternion flips. */
static void bake_warnings(cb_sampler *s, const cb_bake_options *o, const bake_args *a, const cb_palette *p,
                          cb_warnings *w)
{
    const cb_model *m = cb_sampler_model(s);
    cb_model_warnings(m, a->clips == NULL, w);
    if (p->fallback_note[0]) cb_warn(w, "note", "%s", p->fallback_note);
    for (uint32_t c = 0; o->root_motion == CB_ROOT_MOTION_KEEP && c < p->clip_count; ++c) {
        cb_clip_info info;
        cb_error ignored = {0};
        if (p->clips[c].loops &&
            !cb_clip_analyze(s, cb_model_find_animation(m, p->clips[c].name), o->fps, 1, &o->limits, &info, &ignored) &&
            info.ground_speed > 0)
            cb_warn(w, "note", "clip '%s' loops and travels %.3g units/s: blending its last row into its first pulls the "
                    "body back; for crowds moved by the game, bake with --root-motion in-place", p->clips[c].name,
                    info.ground_speed);
    }
    if (p->quat_hemisphere_breaks)
        cb_warn(w, "note", "%u bone(s) turn a full circle over a loop, so their last and first rows lie in opposite "
                "quaternion hemispheres; the shipped shaders flip before blending", p->quat_hemisphere_breaks);
}

/* --format, or OUT's extension: .pal, .exr, or none (a device, a pipe: a .pal, as always);
 * another extension is refused, never guessed. */
static int output_formats(const bake_args *a, bool *want_pal, bool *want_exr, bool *want_ktx2)
{
    if (a->format) {
        if (!parse_formats(a->format, want_pal, want_exr, want_ktx2))
            return cli_usage_error("bake", "--format is pal, exr or pal,exr (any comma-separated set of pal, exr and ktx2), got '%s'",
                                   a->format);
        return 0;
    }
    const char *dot = strrchr(a->output, '.'), *slash = strrchr(a->output, '/');
    const char *ext = dot && (!slash || dot > slash) ? dot : "";
    *want_exr = strcmp(ext, ".exr") == 0;
    *want_ktx2 = strcmp(ext, ".ktx2") == 0;
    *want_pal = strcmp(ext, ".pal") == 0 || !ext[0];
    if (!*want_pal && !*want_exr && !*want_ktx2)
        return cli_usage_error("bake", "%s: unknown output extension '%s'; write OUT.pal, OUT.exr or OUT.ktx2, or give "
                               "--format pal,exr", a->output, ext);
    return 0;
}

int cmd_bake(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CB_ERR_USAGE;
    bake_args a = {0};
    bool help;
    const cli_option options[] = {
        {"-o", "FILE", &a.output, NULL},           {"--output", "FILE", &a.output, NULL},
        {"--format", "pal,exr", &a.format, NULL},  {"--fps", "N", &a.fps, NULL},
        {"--layout", "LAYOUT", &a.layout, NULL},   {"--precision", "PRECISION", &a.precision, NULL},
        {"--max-texture-size", "N", &a.max_size, NULL}, {"--root-motion", "keep|in-place", &a.root_motion, NULL},
        {"--skin", "NAME|INDEX", &a.skin, NULL},   {"--speed-reference", "M_PER_S", &a.speed_ref, NULL},
        {"--exr-compression", "NAME", &a.exr_compression, NULL}, {"--zstd", NULL, NULL, &a.zstd},
        {"--json", NULL, NULL, &a.json},           {"-q", NULL, NULL, &a.quiet},
        {"-j", "N", &a.threads, NULL},             {"--threads", "N", &a.threads, NULL},
        {"--force", NULL, NULL, &a.force},         {"--depfile", "FILE", &a.depfile, NULL},
        {"--manifest", "FILE", &a.manifest, NULL}, {"--max-error", "MM_PER_M", &a.max_error, NULL},
        {"--max-fps", "N", &a.max_fps, NULL},      {"--clip", "A,B", &a.clips, NULL},
        {"--exclude-clip", "A,B", &a.excluded, NULL}, {"--fit-rows", NULL, NULL, &a.fit},
        {"--quiet", NULL, NULL, &a.quiet_long}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &a.model, 1, 1, &help);
    if (help) return fputs(cmd_bake_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    a.quiet |= a.quiet_long;
    if (ends_with(a.model, ".toml")) return bake_catalog(&a, &limits);
    if (!a.output) return cli_usage_error("bake", "-o OUT.pal or -o OUT.exr is required");
    if (a.depfile || a.manifest || a.force)
        return cli_usage_error("bake", "%s is for catalogs (a single bake always writes its outputs)",
                               a.depfile ? "--depfile" : a.manifest ? "--manifest" : "--force");
    bool want_pal = false, want_exr = false, want_ktx2 = false;
    if ((rc = output_formats(&a, &want_pal, &want_exr, &want_ktx2))) return rc;
    int exr_compression = 0;
    if (a.exr_compression && !cb_exr_compression_parse(a.exr_compression, &exr_compression))
        return cli_usage_error("bake", "--exr-compression is none, rle, zips, zip or piz (lossless only)");
    if (a.zstd && !want_pal) return cli_usage_error("bake", "--zstd compresses .pal payloads; EXR takes --exr-compression");
    double speed_ref = 0;
    if (a.speed_ref && (!cli_parse_double(a.speed_ref, &speed_ref) || speed_ref < 0))
        return cli_usage_error("bake", "--speed-reference wants a non-negative speed in m/s");
    cb_bake_options o;
    cb_precision exr_precision = CB_PRECISION_FLOAT;
    if ((rc = parse_options(&a, &o, want_exr, want_ktx2, want_pal, &exr_precision))) return rc;
    double max_mm = 1, max_fps = 60;
    if (a.max_error && (!cli_parse_double(a.max_error, &max_mm) || !(max_mm > 0)))
        return cli_usage_error("bake", "--max-error wants mm per metre of model height");
    if (a.max_fps && (!cli_parse_double(a.max_fps, &max_fps) || !(max_fps >= 2) || max_fps > 1000))
        return cli_usage_error("bake", "--max-fps wants 2..1000");
    if (a.max_error && !(a.fps && strcmp(a.fps, "auto") == 0))
        return cli_usage_error("bake", "--max-error goes with --fps auto");
    o.limits = limits;

    double t0 = now_seconds();
    cb_error err = {0};
    cb_model *m = cli_load_model(a.model, &o.limits, &err);
    if (!m) return cli_report(&err);
    phase_times pt = {now_seconds() - t0, 0};
    int skin = cli_pick_skin(m, a.skin, &err);
    cb_sampler *s = skin >= 0 ? cb_sampler_create(m, skin, &err) : NULL;
    cb_palette p = {0};
    cb_clip_plan *selection = NULL;
    uint32_t selected = 0;
    if (s && !cli_select_clips(m, a.clips, a.excluded, &selection, &selected, &err))
        bake_palette(s, &o, &a, selection, selected, max_mm, max_fps, a.quiet || a.json, &p, &err);
    cb_warnings warnings = {0};
    if (!err.status) bake_warnings(s, &o, &a, &p, &warnings);
    cb_json j;
    if (a.json && !err.status) {
        cb_json_init(&j, stdout);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "model", a.model);
        cb_json_array(&j, "outputs");
    }
    uint64_t hash = err.status ? 0 : input_hash(m, &o, skin, a.zstd, exr_compression);
    static const char *const format_names[3] = {"pal", "exr", "ktx2"};
    for (int f = 0; f < 3 && !err.status; ++f) {
        if ((f == 0 && !want_pal) || (f == 1 && !want_exr) || (f == 2 && !want_ktx2)) continue;
        char path[4096];
        if (a.format) output_path(a.output, format_names[f], path, sizeof path);
        else snprintf(path, sizeof path, "%s", a.output);
        if (f >= 1 && o.precision != exr_precision) { /* the .pal's u16 is no EXR or KTX2 */
            cb_palette_free(&p);
            o.precision = exr_precision;
            if (bake_palette(s, &o, &a, selection, selected, max_mm, max_fps, true, &p, &err)) break;
            hash = input_hash(m, &o, skin, a.zstd, exr_compression);
        }
        double tw = now_seconds();
        if (f == 0) {
            cb_pal_write_options po = {a.zstd, 0, hash, (float)speed_ref, o.root_motion == CB_ROOT_MOTION_IN_PLACE};
            cb_pal_write(path, &p, m, skin, &po, &err);
        } else if (f == 1) {
            cb_exr_write(path, &p, m, skin, exr_compression, hash, (float)speed_ref, &err);
        } else {
            cb_ktx2_write(path, &p, m, skin, hash, (float)speed_ref, &err);
        }
        if (err.status) break;
        pt.write = now_seconds() - tw;
        FILE *fp = fopen(path, "rb");
        size_t bytes = 0;
        if (fp) fseek(fp, 0, SEEK_END), bytes = (size_t)ftell(fp), fclose(fp);
        double seconds = now_seconds() - t0;
        if (a.json) json_output(&j, path, format_names[f], bytes, &p, seconds, &pt);
        else if (!a.quiet) print_summary(path, bytes, &p, seconds);
    }
    if (a.json && !err.status) {
        cb_json_end(&j);
        cli_json_warnings(&j, &warnings);
        cb_json_end(&j);
    } else if (!err.status) {
        cli_print_warnings(&warnings, !a.quiet);
    }
    cb_warnings_free(&warnings);
    free(selection);
    cb_palette_free(&p);
    cb_sampler_free(s);
    cb_model_free(m);
    return err.status ? cli_report(&err) : 0;
}
