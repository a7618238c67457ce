/* cli.c - option parsing and the helpers every subcommand shares. */
#define _DEFAULT_SOURCE /* readlink */
#include "cli.h"
#include "internal/plumbing.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

int cli_exit_code(cb_status status)
{
    switch (status) {
    case CB_OK: return CLI_EXIT_OK;
    case CB_ERR_SETTINGS: return CLI_EXIT_USAGE;
    case CB_ERR_BUDGET: return CLI_EXIT_BUDGET;
    case CB_ERR_INPUT: return CLI_EXIT_INPUT;
    case CB_ERR_LAYOUT: return CLI_EXIT_INPUT; /* the rig cannot be baked as asked */
    case CB_ERR_IO: return CLI_EXIT_IO;
    case CB_ERR_VERIFY: return CLI_EXIT_VERIFY;
    case CB_ERR_INTERNAL: break;
    }
    return CLI_EXIT_INTERNAL;
}

const char *cli_setting_flag(cb_setting setting)
{
    switch (setting) {
    case CB_SETTING_MAX_FRAMES: return "--max-frames";
    case CB_SETTING_MAX_JOINTS: return "--max-joints";
    case CB_SETTING_MAX_PALETTE_BYTES: return "--max-palette-size";
    case CB_SETTING_MAX_FILE_BYTES: return "--max-file-size";
    case CB_SETTING_MAX_ACCESSOR_COUNT: return "--max-accessor-count";
    case CB_SETTING_MAX_TEXTURE_SIZE: return "--max-texture-size";
    case CB_SETTING_LAYOUT: return "--layout";
    case CB_SETTING_PRECISION: return "--precision";
    case CB_SETTING_BATCH: return "--batch";
    case CB_SETTING_SYNC: return "--sync";
    case CB_SETTING_DEFAULT_STATE: return "--default-state";
    case CB_SETTING_ROOT_MOTION: return "--root-motion";
    case CB_SETTING_FPS: return "--fps";
    case CB_SETTING_MAX_FPS: return "--max-fps";
    case CB_SETTING_MAX_ERROR: return "--max-error";
    case CB_SETTING_ALLOW_OVER_BUDGET: return "--allow-over-budget";
    case CB_SETTING_BONE_SPACE: return "--bone-space";
    case CB_SETTING_NONE: break;
    }
    return NULL;
}

const char *cli_error_text(const cb_error *err, char *buf, size_t size)
{
    const char *flag = cli_setting_flag(err->setting);
    snprintf(buf, size, "%s%s%s%s", err->message, flag ? " [" : "", flag ? flag : "", flag ? "]" : "");
    return buf;
}

int cli_report(const cb_error *err)
{
    char text[sizeof err->message + 32];
    fprintf(stderr, "crowdbake: %s\n", cli_error_text(err, text, sizeof text));
    return err->status ? cli_exit_code(err->status) : CLI_EXIT_INTERNAL;
}

int cli_usage_error(const char *command, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "crowdbake %s: ", command);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, " (see 'crowdbake %s --help')\n", command);
    va_end(ap);
    return CLI_EXIT_USAGE;
}

static const cli_option *find_option(const cli_option *options, size_t count, const char *name, size_t len)
{
    for (size_t i = 0; i < count; ++i)
        if (strlen(options[i].name) == len && strncmp(options[i].name, name, len) == 0) return &options[i];
    return NULL;
}

int cli_parse(int argc, char **argv, const cli_option *options, size_t option_count, const char **positional,
              size_t min_positional, size_t max_positional, bool *help)
{
    size_t npos = 0;
    *help = false;
    bool only_positional = false;
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (!only_positional && (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0)) {
            *help = true;
            return 0;
        }
        if (!only_positional && strcmp(arg, "--") == 0) {
            only_positional = true;
            continue;
        }
        if (!only_positional && arg[0] == '-' && arg[1] != '\0') {
            const char *eq = strchr(arg, '=');
            size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
            const cli_option *opt = find_option(options, option_count, arg, len);
            if (!opt) {
                char typed[64];
                snprintf(typed, sizeof typed, "%.*s", (int)len, arg);
                const char *guess = cb_closest_name(typed, &options[0].name, option_count, sizeof options[0]);
                if (guess) return cli_usage_error(argv[0], "unknown option '%s'; did you mean '%s'?", typed, guess);
                return cli_usage_error(argv[0], "unknown option '%s'", typed);
            }
            if (!opt->metavar) {
                if (eq) return cli_usage_error(argv[0], "option %s takes no value", opt->name);
                *opt->flag = true;
                continue;
            }
            if (eq) {
                *opt->value = eq + 1;
            } else {
                if (i + 1 >= argc) return cli_usage_error(argv[0], "option %s needs a value (%s)", opt->name, opt->metavar);
                *opt->value = argv[++i];
            }
            if (strcmp(*opt->value, "-") == 0 && (strcmp(opt->name, "-o") == 0 || strcmp(opt->name, "--output") == 0))
                return cli_usage_error(argv[0], "%s -: writes no standard output (a palette is binary, and its sidecars need a "
                                       "name); name a file, e.g. %s out.%s", opt->name, opt->name,
                                       strcmp(argv[0], "preview") == 0 ? "png" : strcmp(argv[0], "mesh") == 0 ? "glb"
                                       : strcmp(argv[0], "vat") == 0 ? "exr" : "pal");
            continue;
        }
        if (npos >= max_positional) return cli_usage_error(argv[0], "unexpected argument '%s'", arg);
        positional[npos++] = arg;
    }
    if (npos < min_positional) return cli_usage_error(argv[0], "missing argument");
    return 0;
}

bool cli_parse_double(const char *text, double *out)
{
    char *end;
    double v = strtod(text, &end);
    if (end == text || *end) return false;
    *out = v;
    return true;
}

bool cli_parse_u32(const char *text, unsigned *out)
{
    char *end;
    if (text[0] == '-') return false;
    unsigned long v = strtoul(text, &end, 10);
    if (end == text || *end || v > 0xffffffffUL) return false;
    *out = (unsigned)v;
    return true;
}

const char cli_limits_usage[] =
    "\nresource limits (bad or hostile input fails fast; raise them for real assets that need more):\n"
    "  --max-joints N            joints in one skin (default 4096)\n"
    "  --max-frames N            baked frames (default 1048576)\n"
    "  --max-accessor-count N    elements in one glTF accessor (default 16777216)\n"
    "  --max-file-size SIZE      one input file (default 2G)\n"
    "  --max-palette-size SIZE   one palette texture (default 1G)\n";

static bool parse_size(const char *text, uint64_t *out)
{
    char *end;
    double v = strtod(text, &end);
    double mult = *end == 'K' || *end == 'k' ? 1024.0 : *end == 'M' || *end == 'm' ? 1048576.0
                : *end == 'G' || *end == 'g' ? 1073741824.0 : 1.0;
    if (mult > 1) ++end;
    if (end == text || *end || !(v >= 0) || v * mult > 1e18) return false;
    *out = (uint64_t)(v * mult);
    return true;
}

int cli_take_limits(int *argc, char **argv, cb_limits *limits)
{
    static const char *const names[] = {"--max-joints", "--max-frames", "--max-accessor-count", "--max-file-size",
                                        "--max-palette-size"};
    *limits = cb_default_limits();
    int kept = 1;
    for (int i = 1; i < *argc; ++i) {
        int which = -1;
        const char *value = NULL;
        for (int k = 0; k < 5 && which < 0; ++k) {
            size_t n = strlen(names[k]);
            if (strncmp(argv[i], names[k], n) != 0) continue;
            if (argv[i][n] == '=') which = k, value = argv[i] + n + 1;
            else if (!argv[i][n]) which = k, value = i + 1 < *argc ? argv[++i] : NULL;
        }
        if (which < 0) {
            argv[kept++] = argv[i];
            continue;
        }
        uint64_t v = 0; /* (GCC 12 under -fsanitize=thread at -O1 cannot see that ok guards it) */
        unsigned u = 0;
        bool ok = value && (which >= 3 ? parse_size(value, &v) : cli_parse_u32(value, &u));
        if (!ok || (which < 3 && u == 0) || (which >= 3 && v == 0))
            return cli_usage_error(argv[0], "%s wants a positive %s", names[which], which >= 3 ? "size (e.g. 512M)" : "integer");
        if (which == 0) limits->max_joints = u;
        if (which == 1) limits->max_frames = u;
        if (which == 2) limits->max_accessor_count = u;
        if (which == 3) limits->max_file_bytes = v;
        if (which == 4) limits->max_palette_bytes = v;
    }
    *argc = kept;
    argv[kept] = NULL;
    return 0;
}

static bool has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* What a file that is not glTF holds, from its first bytes, else from its name: the formats
 * artists export before glTF. NULL when it may be glTF (the loader then says what is wrong). */
static const char *foreign_format(const char *path)
{
    char head[24] = {0};
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t n = fread(head, 1, sizeof head, f);
    fclose(f);
    if (n >= 4 && (memcmp(head, "glTF", 4) == 0 || head[0] == '{')) return NULL;
    if (n >= 18 && memcmp(head, "Kaydara FBX Binary", 18) == 0) return "an FBX file";
    if (n >= 5 && memcmp(head, "; FBX", 5) == 0) return "an FBX file (ASCII)";
    if (n >= 7 && memcmp(head, "BLENDER", 7) == 0) return "a Blender .blend file";
    if (n >= 4 && memcmp(head, "\x89PNG", 4) == 0) return "a PNG image";
    if (n >= 3 && memcmp(head, "\xff\xd8\xff", 3) == 0) return "a JPEG image";
    static const char *const by_name[][2] = {{".fbx", "an FBX file"}, {".obj", "a Wavefront OBJ file"},
                                              {".blend", "a Blender .blend file"}, {".dae", "a COLLADA file"},
                                              {".png", "a PNG image"}, {".usd", "a USD file"}, {".usdz", "a USD file"}};
    for (size_t i = 0; i < sizeof by_name / sizeof by_name[0]; ++i)
        if (has_extension(path, by_name[i][0])) return by_name[i][1];
    return NULL;
}

static cb_model *load_model(const char *path, const cb_limits *limits, cb_error *err);

cb_model *cli_load_model(const cli_output *out, const char *path, const cb_limits *limits, cb_error *err)
{
    double t0 = cli_seconds();
    cb_model *m = load_model(path, limits, err);
    if (m && out)
        cli_verbose(out, "read %s in %.3f s: %u skin%s, %u node%s, %u clip%s", path, cli_seconds() - t0, m->skin_count,
                    m->skin_count == 1 ? "" : "s", m->node_count, m->node_count == 1 ? "" : "s", m->animation_count,
                    m->animation_count == 1 ? "" : "s");
    return m;
}

/* What crowdbake itself wrote, given where a model is wanted: a palette (kind, by its first bytes) or
 * a roster manifest (its "schema"); NULL for anything else. Never "not a valid glTF 2.0 file: Root
 * element is not a JSON object" for a bake's own output. */
static const char *crowdbake_output(const char *path, cli_file_kind kind)
{
    switch (kind) {
    case CLI_FILE_PAL: return "a crowdbake palette (.pal)";
    case CLI_FILE_EXR: return "an OpenEXR image (crowdbake writes palettes and VATs as these)";
    case CLI_FILE_KTX2: return "a KTX2 texture (crowdbake writes palettes as these)";
    case CLI_FILE_MODEL: break;
    default: return NULL;
    }
    char head[128] = {0}; /* the manifest's "schema" comes first (cli/roster/roster_files.c) */
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t n = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    head[n] = 0;
    return strstr(head, "\"crowdbake-roster/") ? "a roster manifest (crowdbake bake writes it from a catalog)" : NULL;
}

static cb_model *load_model(const char *path, const cb_limits *limits, cb_error *err)
{
    cli_file_kind kind = cli_file_kind_of(path);
    if (kind == CLI_FILE_UNKNOWN && has_extension(path, ".toml")) {
        cb_fail(err, CB_ERR_INPUT, "%s: a catalog, not a model: this command reads one model (an [animal.NAME]'s model); "
                "'crowdbake bake' and 'crowdbake report' read catalogs", path);
        return NULL;
    }
    const char *own = crowdbake_output(path, kind);
    if (own) {
        bool palette = kind == CLI_FILE_PAL || kind == CLI_FILE_KTX2; /* (an EXR may be a VAT: inspect reads palettes) */
        cb_fail(err, CB_ERR_INPUT, "%s: not a model but %s: give the glTF model it was baked from (.glb or .gltf), or the "
                "catalog (.toml)%s%s%s", path, own, palette ? "; 'crowdbake inspect " : "", palette ? path : "",
                palette ? "' shows what it holds" : "");
        return NULL;
    }
    const char *foreign = foreign_format(path);
    if (foreign) {
        cb_fail(err, CB_ERR_INPUT, "%s: not glTF (%s): convert it with FBX2glTF (FBX2glTF -b -i IN.fbx -o OUT) or Blender "
                "(File > Export > glTF 2.0, format .glb, with the armature and its animations), then give the .glb",
                path, foreign);
        return NULL;
    }
    return cb_gltf_load(path, limits, err);
}

int cli_pick_skin(const cb_model *model, const char *skin_option, cb_error *err)
{
    if (model->skin_count == 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: has no skin, so there are no joints to bake (export the armature with the mesh)",
                       model->source),
               -1;
    if (skin_option) {
        int s = cb_model_find_skin(model, skin_option);
        if (s < 0)
            cb_fail(err, CB_ERR_SETTINGS, "%s: has no skin '%s' (it has %u; see 'crowdbake info')", model->source, skin_option,
                    model->skin_count);
        return s;
    }
    if (model->skin_count > 1) {
        /* Prefer the only skin that a mesh uses. */
        int used = -1, uses = 0;
        for (uint32_t s = 0; s < model->skin_count; ++s)
            if (cb_model_skin_vertex_count(model, (int32_t)s) > 0) used = (int)s, ++uses;
        if (uses == 1) return used;
        cb_fail(err, CB_ERR_SETTINGS, "%s: has %u skins; choose one with --skin NAME|INDEX (see 'crowdbake info')",
                model->source, model->skin_count);
        return -1;
    }
    return 0;
}

cli_file_kind cli_file_kind_of(const char *path)
{
    unsigned char head[12] = {0};
    FILE *f = fopen(path, "rb");
    if (!f) return CLI_FILE_MISSING;
    size_t n = fread(head, 1, sizeof head, f);
    fclose(f);
    static const unsigned char exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};
    if (n >= 8 && memcmp(head, "CBPAL\r\n\x1a", 8) == 0) return CLI_FILE_PAL;
    if (n >= 4 && memcmp(head, exr_magic, 4) == 0) return CLI_FILE_EXR;
    if (n >= 12 && memcmp(head, "\xabKTX 20\xbb\r\n\x1a\n", 12) == 0) return CLI_FILE_KTX2;
    if (n >= 4 && memcmp(head, "glTF", 4) == 0) return CLI_FILE_MODEL;
    size_t i = 0; /* a .gltf is JSON: an object */
    while (i < n && (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n')) ++i;
    if (i < n && head[i] == '{') return CLI_FILE_MODEL;
    if (n >= 3 && memcmp(head, "\xef\xbb\xbf", 3) == 0) return CLI_FILE_MODEL; /* JSON with a byte-order mark */
    return CLI_FILE_UNKNOWN;
}

static bool is_palette(cli_file_kind k) { return k == CLI_FILE_PAL || k == CLI_FILE_EXR || k == CLI_FILE_KTX2; }

/* The arguments are MODEL PALETTE: says which one is wrong and how, before anything is read. */
static cb_status check_kinds(const char *command, const char *model_path, const char *palette_path, cb_error *err)
{
    cli_file_kind mk = cli_file_kind_of(model_path), pk = cli_file_kind_of(palette_path);
    if (mk == CLI_FILE_MISSING || pk == CLI_FILE_MISSING)
        return cb_fail(err, CB_ERR_IO, "%s: cannot open it", mk == CLI_FILE_MISSING ? model_path : palette_path);
    if (mk != CLI_FILE_MODEL)
        return cb_fail(err, CB_ERR_SETTINGS, "%s: is %s, not a glTF model; 'crowdbake %s MODEL PALETTE' takes the .glb/.gltf "
                       "first", model_path, is_palette(mk) ? "a palette" : "neither glTF nor a palette", command);
    if (!is_palette(pk))
        return cb_fail(err, CB_ERR_SETTINGS, "%s: is %s, not a palette; 'crowdbake %s MODEL PALETTE' takes the .pal, .exr "
                       "or .ktx2 that 'crowdbake bake' wrote second", palette_path, pk == CLI_FILE_MODEL ? "a glTF model" : "neither a "
                       "palette nor glTF", command);
    return CB_OK;
}

static cb_status open_palette(const char *path, cli_baked *b, cb_error *err)
{
    if (cli_file_kind_of(path) == CLI_FILE_KTX2) {
        if (cb_ktx2_read_palette(path, &b->ktx2, err)) return err->status;
        b->is_ktx2 = true;
        b->view = b->ktx2.palette;
        b->texels = b->ktx2.palette.texels;
        return CB_OK;
    }
    if (cli_file_kind_of(path) == CLI_FILE_EXR) {
        if (cb_exr_read_palette(path, &b->exr, err)) return err->status;
        b->is_exr = true;
        b->view = b->exr.palette;
        b->texels = b->exr.palette.texels;
        return CB_OK;
    }
    char msg[512];
    if (cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &b->pal, msg, sizeof msg)) return cb_fail(err, CB_ERR_INPUT, "%s", msg);
    if (cb_palette_view(&b->pal, &b->view, err)) {
        cbpal_close(&b->pal);
        return err->status;
    }
    b->texels = b->pal.texels;
    b->pal_open = true;
    return CB_OK;
}

void cli_baked_close(cli_baked *b)
{
    if (b->is_exr) cb_exr_palette_free(&b->exr);
    else if (b->is_ktx2) cb_ktx2_palette_free(&b->ktx2);
    else if (b->pal_open) cb_palette_view_free(&b->view), cbpal_close(&b->pal);
    cb_model_free(b->model);
    memset(b, 0, sizeof *b);
}

cb_status cli_open_baked(const cli_output *out, const char *command, const char *model_path, const char *palette_path,
                         const cb_limits *limits, const char *skin_option, cli_baked *b, cb_error *err)
{
    memset(b, 0, sizeof *b);
    if (is_palette(cli_file_kind_of(model_path)) && cli_file_kind_of(palette_path) == CLI_FILE_MODEL) {
        /* `preview PALETTE MODEL` was the documented order before both commands took MODEL PALETTE:
         * scripts written for it keep working, with a note. */
        if (!out->quiet) fprintf(stderr, "crowdbake: note: '%s %s %s' is the old order, still accepted; write 'crowdbake %s MODEL "
                "PALETTE'\n", command, model_path, palette_path, command);
        const char *swap = model_path;
        model_path = palette_path, palette_path = swap;
    }
    double t0 = cli_seconds();
    if (check_kinds(command, model_path, palette_path, err) || open_palette(palette_path, b, err)) return err->status;
    cli_verbose(out, "read %s in %.3f s: %s/%s, %u bones, %u rows, %u clip%s", palette_path, cli_seconds() - t0,
                cb_layout_name(b->view.layout), cb_precision_name(b->view.precision), b->view.bone_count, b->view.rows,
                b->view.clip_count, b->view.clip_count == 1 ? "" : "s");
    b->model = cli_load_model(out, model_path, limits, err);
    b->skin = b->model ? cli_pick_skin(b->model, skin_option, err) : -1;
    if (b->skin >= 0 && b->model->skins[b->skin].joint_count != b->view.bone_count)
        cb_fail(err, CB_ERR_INPUT, "%s: its skin has %u joints, %s has %u bones: not its palette", model_path,
                b->model->skins[b->skin].joint_count, palette_path, b->view.bone_count);
    if (err->status) cli_baked_close(b);
    return err->status;
}

void cli_executable(char *path, size_t size)
{
    ssize_t n = size ? readlink("/proc/self/exe", path, size - 1) : 0;
    if (size) path[n > 0 ? n : 0] = 0;
}
