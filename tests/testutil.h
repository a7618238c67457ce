/* testutil.h - shared helpers for the cmocka tests. Tests run from the repository root. */
#ifndef CB_TESTUTIL_H
#define CB_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "crowdbake/gltf.h"
#include "crowdbake/palette.h"

/* The build being tested (the Makefile passes its BUILD): each build's tests write their files
 * under TEST_TMP, so the normal and the sanitizer passes can run side by side. */
#ifndef BUILD_DIR
#define BUILD_DIR "build"
#endif
#define TEST_TMP BUILD_DIR "/tmp-tests"

/* The command's exit codes, as the README's "Exit codes" table gives them: what a test of the
 * command checks against, rather than the library's cb_status values (which are not exit codes). */
#define EXIT_USAGE 2
#define EXIT_BUDGET 3
#define EXIT_INPUT 4
#define EXIT_IO 5
#define EXIT_VERIFY 6

/* ../shared beside the checkout, or $CROWDBAKE_SHARED. */
static inline const char *shared_dir(void)
{
    const char *env = getenv("CROWDBAKE_SHARED");
    return env ? env : "../shared";
}

static inline void shared_path(char *out, size_t size, const char *rel)
{
    int n = snprintf(out, size, "%s/%s", shared_dir(), rel);
    if (n < 0 || (size_t)n >= size) fail_msg("path too long: %s", rel);
    FILE *f = fopen(shared_dir(), "r");
    if (!f) fail_msg("%s: no such directory; the tests need the shared third-party assets and reference matrices "
                     "there (clone the repository beside them, or set CROWDBAKE_SHARED=DIR)", shared_dir());
    fclose(f);
}

static inline const char *samples_dir(void)
{
    const char *env = getenv("SAMPLES");
    return env ? env : BUILD_DIR "/samples";
}

static inline const char *crowdbake_exe(void)
{
    const char *env = getenv("CROWDBAKE");
    return env ? env : BUILD_DIR "/crowdbake";
}

/* A whole file, NUL-terminated (so text can be used as a string); *size gets its length. */
static inline char *read_whole_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    assert_int_equal(fread(s, 1, (size_t)n, f), (size_t)n);
    s[n] = '\0';
    fclose(f);
    if (size) *size = (size_t)n;
    return s;
}

/* Writes text to a file (a catalog, a Makefile) or fails the test. */
static inline void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Loads a model or fails the test with the loader's message. */
static inline cb_model *load_or_fail(const char *path)
{
    cb_error err = {0};
    cb_model *m = cb_gltf_load(path, NULL, &err);
    if (!m) fail_msg("cannot load %s: %s", path, err.message);
    return m;
}

static inline cb_model *load_shared(const char *rel)
{
    char path[1024];
    shared_path(path, sizeof path, rel);
    return load_or_fail(path);
}

/* Runs a shell command; returns its exit status (or -1). Output goes to `out` if given. */
#define COUNT_OF(a) (sizeof(a) / sizeof((a)[0]))

/* Every model of ../shared/assets that loads (MANIFEST.md); the assimp ones have no skin. */
static const char *const shared_models[] = {
    "assets/fox-bevy/Fox.glb",
    "assets/derived-fox/Fox.draco.glb",
    "assets/derived-fox/Fox.meshopt.glb",
    "assets/derived-fox/Fox.quantized.glb",
    "assets/derived-fox/separate/Fox.gltf",
    "assets/riggedfigure-raylib/rigged_figure.glb",
    "assets/simpleskin-bevy/SimpleSkin.gltf",
    "assets/simpleskin-luanti/gltf_simple_skin.gltf",
    "assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf",
    "assets/spider-animated-luanti/gltf_spider_animated.gltf",
    "assets/derived-spider-luanti/gltf_spider_animated.draco.glb",
    "assets/derived-spider-luanti/gltf_spider_animated.meshopt.glb",
    "assets/derived-spider-luanti/gltf_spider_animated.quantized.glb",
    "assets/derived-spider-luanti/separate/gltf_spider_animated.gltf",
    "assets/robot-quaternius-raylib/robot.glb",
    "assets/multitrack-luanti/gltf_multi_track_1.glb",
    "assets/assimp-animation-interpolation/animation_interpolation_linear.gltf",
    "assets/assimp-animation-interpolation/animation_interpolation_step.gltf",
    "assets/assimp-animation-interpolation/animation_interpolation_cubic.gltf",
};

/* The project's own sample animals, build/samples/NAME.glb. */
static const char *const sample_names[] = {"quadruped", "fish", "bird"};

static inline void sample_path(char *out, size_t size, const char *name)
{
    snprintf(out, size, "%s/%s.glb", samples_dir(), name);
}

static inline int run_command(const char *cmd, char *out, size_t out_size)
{
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    size_t used = 0;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) {
        if (out && used + 1 < out_size) {
            size_t take = n < out_size - used - 1 ? n : out_size - used - 1;
            memcpy(out + used, buf, take);
            used += take;
        }
    }
    if (out && out_size) out[used] = '\0';
    int status = pclose(p);
    return status >= 0 && (status & 0x7f) == 0 ? (status >> 8) & 0xff : -1;
}

/* run_command on a printf-formatted command line. */
static inline int run(char *out, size_t size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static inline int run(char *out, size_t size, const char *fmt, ...)
{
    char cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    return run_command(cmd, out, size);
}

/* Runs `crowdbake ARGS 2>&1`, ARGS printf-formatted; returns its exit status, its output in `out` if given. */
static inline int run_crowdbake(char *out, size_t size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static inline int run_crowdbake(char *out, size_t size, const char *fmt, ...)
{
    char args[2048], cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof cmd, "%s %s 2>&1", crowdbake_exe(), args);
    return run_command(cmd, out, size);
}

static inline bool exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* DIR/NAME.glb, a link to the model at `path` (by its real path: a relative one would not hold from
 * DIR). The browser checks serve DIR, the model and its bakes side by side. */
static inline void link_model(const char *path, const char *dir, const char *name)
{
    char out[1024];
    if (run(out, sizeof out, "ln -s \"$(realpath %s)\" %s/%s.glb 2>&1", path, dir, name) != 0)
        fail_msg("cannot link %s as %s/%s.glb: %s", path, dir, name, out);
}

/* The number after the next "key": from `at`, in a check's JSON output (the browser checks print one
 * JSON line). */
static inline double json_number_after(const char *at, const char *key)
{
    char pattern[96];
    snprintf(pattern, sizeof pattern, "\"%s\":", key);
    if (!(at = strstr(at, pattern))) fail_msg("no \"%s\" in the rest of the check's output", key);
    return atof(at + strlen(pattern));
}

/* The number after "key": inside the object that follows "section": in a check's JSON output. */
static inline double json_number_in(const char *json, const char *section, const char *key)
{
    char pattern[96];
    snprintf(pattern, sizeof pattern, "\"%s\":", section);
    const char *at = strstr(json, pattern);
    if (!at) fail_msg("no \"%s\" in the check's output: %.2000s", section, json);
    return json_number_after(at + strlen(pattern), key);
}

/* The npm packages of tests/tools/validator (the Khronos glTF validator, ajv), which `make test`
 * installs from their package-lock before any test runs. */
static inline void require_node_validators(void)
{
    FILE *f = fopen("tests/tools/validator/node_modules/.package-lock.json", "r");
    if (!f) fail_msg("tests/tools/validator: npm packages not installed (make test installs them; or: cd tests/tools/validator && npm ci)");
    fclose(f);
}

/* A JSON file against its schema (docs/NAME.schema.json, ajv): fails naming what does not match. */
static inline void assert_schema_valid(const char *schema, const char *file)
{
    char cmd[4096], log[4096];
    require_node_validators();
    snprintf(cmd, sizeof cmd, "node tests/tools/validator/validate_schema.mjs %s %s 2>&1", schema, file);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
}

/* The visible error (cb_palette.visible_error) of `animation` baked alone at `fps`, its rows fitted
 * or sampled: measured in full with goal 0; with goal > 0 only as far as the goal needs (exact
 * within it, a lower bound, still above it, past it). */
static inline double clip_visible_error(cb_sampler *s, int32_t animation, double fps, bool fit, double goal)
{
    cb_bake_options o = cb_default_bake_options();
    o.fps = fps;
    o.error_goal = goal;
    cb_clip_plan plan = {animation, NULL, -1, fps, fit, false, 0, NULL};
    cb_palette p;
    cb_error err = {0};
    assert_int_equal(cb_palette_bake(s, &o, &plan, 1, &p, &err), CB_OK);
    double e = p.visible_error;
    cb_palette_free(&p);
    return e;
}

#endif
