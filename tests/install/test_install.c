/* test_install.c - libcrowdbake as another project uses it: `make install` into a folder, then
 * a program outside the tree (tests/install/bake_model.c) built against the installed files
 * with pkg-config and with CMake's find_package, baking Fox through the public API to the very
 * bytes `crowdbake bake` writes; and crowdbake_bake_roster() with real CMake + Ninja: a second
 * build does nothing, a changed model re-bakes only its type. Also what else is installed: the
 * man page renders cleanly, the completions know every option of every command, and the Godot
 * addon's zip is reproducible.
 * Runs in the normal build only: a program linked against the sanitizer build's library
 * would need the sanitizer runtime too. */
#define _DEFAULT_SOURCE
#include "testutil.h"
#include "view_server.h"

#include <ctype.h>
#include <limits.h>
#include <stdarg.h>
#include <sys/stat.h>
#include <unistd.h>

#define TMP TEST_TMP "/install"

static char root[PATH_MAX], prefix[PATH_MAX + 64], fox[PATH_MAX];

/* Runs `cmd` (stderr folded in) with make's own variables out of the way. */
static int sh(char *out, size_t size, const char *fmt, ...)
{
    char cmd[8192], line[8300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    snprintf(line, sizeof line, "env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL sh -c '%s' 2>&1", cmd);
    static char ignored[65536];
    return run_command(line, out ? out : ignored, out ? size : sizeof ignored);
}

static int setup(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    return 0;
#endif
    char rel[PATH_MAX];
    shared_path(rel, sizeof rel, "assets/fox-bevy/Fox.glb");
    if (!getcwd(root, sizeof root) || !realpath(rel, fox)) return -1;
    if (system("rm -rf " TMP " && mkdir -p " TMP)) return -1;
    snprintf(prefix, sizeof prefix, "%s/" TMP "/prefix", root);
    static char out[65536];
    if (sh(out, sizeof out, "make --no-print-directory BUILD=%s PREFIX=%s install", BUILD_DIR, prefix) != 0) {
        fprintf(stderr, "make install failed:\n%s", out);
        return -1;
    }
    return 0;
}

static bool skip_under_sanitizers(void)
{
#if defined(__SANITIZE_ADDRESS__)
    return true;
#else
    return false;
#endif
}

/* The bake the command itself writes at its default settings, to compare the library's bytes with:
 * the speed reference too is decided in the library (locomotion.h), so a program linking it
 * records the same one as the command. */

/* The build tree's command's bake of the same Fox, with `options`. */
static void reference_bake(const char *out, const char *options)
{
    char cmd[4 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s -q %s", crowdbake_exe(), fox, out, options);
    assert_int_equal(system(cmd), 0);
}

static void assert_same_file(const char *a, const char *b)
{
    size_t na, nb;
    char *x = read_whole_file(a, &na), *y = read_whole_file(b, &nb);
    if (na != nb || memcmp(x, y, na) != 0) fail_msg("%s (%zu bytes) differs from %s (%zu bytes)", a, na, b, nb);
    free(x), free(y);
}

/* DESTDIR stages the tree without writing DESTDIR into what is installed. */
static void test_destdir_layout(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    static char out[65536];
    if (sh(out, sizeof out, "make --no-print-directory BUILD=%s PREFIX=/opt/cb DESTDIR=%s/" TMP "/stage install", BUILD_DIR,
           root) != 0)
        fail_msg("%s", out);
    static const char *const files[] = {
        "bin/crowdbake", "lib/libcrowdbake.a", "lib/libcrowdbake.so", "lib/libcrowdbake.so.3",
        "include/crowdbake/crowdbake.h", "include/crowdbake/bake.h", "include/crowdbake_pal.h",
        "include/crowdbake_pal_runtime.h",
        "lib/pkgconfig/crowdbake.pc", "lib/cmake/crowdbake/crowdbakeConfig.cmake",
        "lib/cmake/crowdbake/crowdbakeConfigVersion.cmake", "lib/cmake/crowdbake/CrowdbakeRoster.cmake",
        "share/man/man1/crowdbake.1", "share/bash-completion/completions/crowdbake", "share/zsh/site-functions/_crowdbake",
        "share/crowdbake/viewer/viewer.html", "share/crowdbake/viewer/serve.py", "share/crowdbake/web/crowdbake_pal.mjs",
        "share/crowdbake/web/node_modules/three/build/three.module.js", "share/crowdbake/web/node_modules/fzstd/esm/index.mjs",
        "share/crowdbake/glsl/crowdbake_palette.glsl",
        "share/crowdbake/crowdbake-godot-addon.zip", "share/crowdbake/com.crowdbake.palette.tgz",
        "share/crowdbake/hlsl/crowdbake_palette.hlsl"};
    for (size_t i = 0; i < COUNT_OF(files); ++i) {
        char path[PATH_MAX * 2];
        snprintf(path, sizeof path, TMP "/stage/opt/cb/%s", files[i]);
        if (!exists(path)) fail_msg("make install did not install %s", path);
    }
    char *pc = read_whole_file(TMP "/stage/opt/cb/lib/pkgconfig/crowdbake.pc", NULL);
    if (!strstr(pc, "prefix=/opt/cb\n") || strstr(pc, "stage")) fail_msg("crowdbake.pc:\n%s", pc);
    free(pc);
    /* The shared library names its dependencies, so -lcrowdbake alone links. */
    assert_int_equal(sh(out, sizeof out, "readelf -d " TMP "/stage/opt/cb/lib/libcrowdbake.so.3"), 0);
    if (!strstr(out, "(SONAME)") || !strstr(out, "libcrowdbake.so.3") || !strstr(out, "libzstd")) fail_msg("%s", out);
}

/* The installed shared library exports exactly what its installed headers declare: every
 * CROWDBAKE_API function and object, in the version node CROWDBAKE_3, and nothing else (no C++
 * internals of the glTF adapter or its dependencies, no library-private helpers). */
static void test_shared_library_exports_only_its_api(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    static char out[65536];
    if (sh(out, sizeof out,
           "python3 tests/tools/abi_symbols.py %s/lib/libcrowdbake.so.3 %s/include/crowdbake %s/include/crowdbake_pal.h",
           prefix, prefix, prefix) != 0)
        fail_msg("%s", out);
    unsigned exported = 0;
    if (!strstr(out, "exported symbols") || sscanf(strstr(out, ": ") + 2, "%u", &exported) != 1) fail_msg("%s", out);
    /* The stable tier: what a game or pipeline needs (model, sampling, palettes, the bake job and
     * its table of outputs, runtime, VAT and budget), about 120 functions and three tables. The
     * library exported 700 symbols before its visibility was set, 411 of them C++ (tinygltf,
     * Draco, RapidJSON, cbgltf::), and 157 functions before the tool's plumbing (the JSON writer,
     * atomic files, arenas, name parsers and lookups, sentences) became internal (src/internal/).
     * API 3.0 added the locomotion decisions, planting feet and the per-row travel (153). */
    if (exported < 100 || exported > 170) fail_msg("%u exported symbols: %s", exported, out);
}

/* A program outside the tree, through pkg-config: the same bytes as the command. It runs as
 * built, with no LD_LIBRARY_PATH and no -rpath of its own: crowdbake.pc carries the rpath. */
static void test_pkg_config_program_bakes_fox(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    static char out[65536];
    int rc = sh(out, sizeof out,
                "export PKG_CONFIG_PATH=%s/lib/pkgconfig && cc -std=c11 -Wall -Wextra -Werror -o " TMP "/bake_model "
                "tests/install/bake_model.c $(pkg-config --cflags --libs crowdbake) && "
                "env -u LD_LIBRARY_PATH " TMP "/bake_model %s " TMP "/pkg.pal",
                prefix, fox);
    if (rc != 0) fail_msg("%s", out);
    /* The default bake: error-bounded local rows, Fox's three clips in 127 rows (its Run timed). */
    if (!strstr(out, "127 rows, 24 bones, qpos/u16") || !strstr(out, "read back: 48x127 texels")) fail_msg("%s", out);
    reference_bake(TMP "/reference.pal", "");
    assert_same_file(TMP "/pkg.pal", TMP "/reference.pal");
    /* It is the installed library that ran, not one from the build tree. */
    assert_int_equal(sh(out, sizeof out, "ldd " TMP "/bake_model"), 0);
    char want[PATH_MAX * 2];
    snprintf(want, sizeof want, "%s/lib/libcrowdbake.so.3", prefix);
    if (!strstr(out, want)) fail_msg("bake_model does not use %s:\n%s", want, out);
}

/* The command is a client like any other: its objects link against the installed shared
 * library, which exports only the stable tier; the internal tier's plumbing (src/internal/) is
 * not exported, so the link fails without it, and takes it from the installed static library
 * (only the objects the shared library lacks). That command bakes Fox to the same bytes. */
static void test_tool_links_against_the_installed_library(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    static char out[65536];
    int rc = sh(out, sizeof out,
                "c++ -o " TMP "/crowdbake_no_internal %s/obj/cli/*.o %s/libcrowdbake_tool.a -L%s/lib -lcrowdbake "
                "$(pkg-config --libs tomlplusplus libpng) -ldl -lpthread -lm 2>&1",
                BUILD_DIR, BUILD_DIR, prefix);
    if (rc == 0 || !strstr(out, "undefined reference to `cb_json_init'") ||
        !strstr(out, "undefined reference to `cb_closest_name'"))
        fail_msg("the internal tier is exported:\n%s", out);
    rc = sh(out, sizeof out,
                "c++ -o " TMP "/crowdbake_shared %s/obj/cli/*.o %s/libcrowdbake_tool.a -L%s/lib -lcrowdbake "
                "%s/lib/libcrowdbake.a -Wl,-rpath,%s/lib $(pkg-config --libs simdjson draco OpenEXR libzstd tomlplusplus "
                "libpng) -lmeshoptimizer -ldl -lpthread -lm && "
                TMP "/crowdbake_shared bake %s -o " TMP "/shared.pal -q && ldd " TMP "/crowdbake_shared",
                BUILD_DIR, BUILD_DIR, prefix, prefix, prefix, fox);
    if (rc != 0) fail_msg("%s", out);
    char want[PATH_MAX * 2];
    snprintf(want, sizeof want, "%s/lib/libcrowdbake.so.3", prefix);
    if (!strstr(out, want)) fail_msg("the command does not use %s:\n%s", want, out);
    reference_bake(TMP "/reference-shared.pal", "");
    assert_same_file(TMP "/shared.pal", TMP "/reference-shared.pal");
}

/* The same program through find_package(crowdbake) and crowdbake::crowdbake. */
static void test_cmake_program_bakes_fox(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    char text[4 * PATH_MAX];
    assert_int_equal(system("mkdir -p " TMP "/cmake-program"), 0);
    snprintf(text, sizeof text,
             "cmake_minimum_required(VERSION 3.20)\nproject(bake_model C)\nfind_package(crowdbake 0.1 REQUIRED)\n"
             "add_executable(bake_model %s/tests/install/bake_model.c)\n"
             "target_link_libraries(bake_model PRIVATE crowdbake::crowdbake)\n", root);
    write_text(TMP "/cmake-program/CMakeLists.txt", text);
    static char out[65536];
    int rc = sh(out, sizeof out,
                "cmake -G Ninja -S " TMP "/cmake-program -B " TMP "/cmake-program/build -DCMAKE_PREFIX_PATH=%s && "
                "ninja -C " TMP "/cmake-program/build && " TMP "/cmake-program/build/bake_model %s " TMP "/cmake.pal",
                prefix, fox);
    if (rc != 0) fail_msg("%s", out);
    reference_bake(TMP "/reference.pal", "");
    assert_same_file(TMP "/cmake.pal", TMP "/reference.pal");
}

static view_server server; /* stopped by the teardown too, when a check fails half-way */

static int stop_server(void **state)
{
    (void)state;
    if (server.pid > 0) view_stop(&server);
    server.pid = 0;
    return 0;
}

/* The installed command's `view`, run from a folder outside the source tree, serves the
 * installed viewer (PREFIX/share/crowdbake/viewer, web and glsl) and every file the page imports. */
static void test_installed_view_serves_the_viewer(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    char away[] = "/tmp/crowdbake-view-XXXXXX", exe[PATH_MAX + 96], fish[PATH_MAX], rel[PATH_MAX], cache[PATH_MAX + 16];
    if (!mkdtemp(away)) fail_msg("mkdtemp");
    snprintf(rel, sizeof rel, "%s/fish.glb", samples_dir());
    if (!realpath(rel, fish)) fail_msg("%s: missing", rel);
    snprintf(exe, sizeof exe, "%s/bin/crowdbake", prefix);
    snprintf(cache, sizeof cache, "%s/cache", away);
    if (view_start(&server, exe, fish, cache, away)) fail_msg("no URL from the installed crowdbake view:\n%s", server.printed);
    char host[64], answer[1 << 16];
    snprintf(host, sizeof host, "127.0.0.1:%u", server.port);
    static const char *const pages[] = {"/viewer/viewer.html", "/viewer/viewer.mjs", "/web/crowdbake_vat.mjs",
                                        "/web/node_modules/three/build/three.module.js",
                                        "/web/node_modules/three/examples/jsm/loaders/GLTFLoader.js",
                                        "/web/node_modules/three/examples/jsm/utils/BufferGeometryUtils.js",
                                        "/web/node_modules/fzstd/esm/index.mjs", "/glsl/crowdbake_palette.glsl",
                                        "/view.json"};
    for (size_t i = 0; i < COUNT_OF(pages); ++i) {
        assert_int_equal(http_get(server.port, pages[i], host, answer, sizeof answer), 0);
        if (strncmp(answer, "HTTP/1.0 200 ", 13)) fail_msg("GET %s: %.300s", pages[i], answer);
    }
    /* And it is the installed copy that is served, not the source tree's. */
    char link[PATH_MAX + 32], target[PATH_MAX], want[PATH_MAX + 128];
    snprintf(link, sizeof link, "%s/site/web", cache);
    ssize_t n = readlink(link, target, sizeof target - 1);
    target[n > 0 ? n : 0] = 0;
    snprintf(want, sizeof want, "%s/share/crowdbake/web", prefix);
    char want_real[PATH_MAX];
    if (!realpath(want, want_real) || strcmp(target, want_real)) fail_msg("the site's web/ is %s, not %s", target, want);
    assert_int_equal(view_stop(&server), 0);
    server.pid = 0;
    char cmd[PATH_MAX + 16];
    snprintf(cmd, sizeof cmd, "rm -rf %s", away);
    assert_int_equal(system(cmd), 0);
}

static struct timespec mtime(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) fail_msg("%s: missing", path);
    return st.st_mtim;
}

static bool same_time(struct timespec a, struct timespec b) { return a.tv_sec == b.tv_sec && a.tv_nsec == b.tv_nsec; }

static void ninja_build(const char *dir, bool expect_work)
{
    static char out[65536];
    if (sh(out, sizeof out, "ninja -C %s/build", dir) != 0) fail_msg("%s", out);
    bool idle = strstr(out, "ninja: no work to do.") != NULL;
    if (idle == expect_work) fail_msg("expected %s:\n%s", expect_work ? "a bake" : "no work", out);
}

/* crowdbake_bake_roster() with real CMake and Ninja. */
static void test_cmake_roster_rebakes_only_what_changed(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    const char *dir = TMP "/cmake-roster";
    char cmd[4 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "mkdir -p %s/assets && cp %s/fish.glb %s/bird.glb %s/assets/", dir, samples_dir(),
             samples_dir(), dir);
    assert_int_equal(system(cmd), 0);
    write_text(TMP "/cmake-roster/catalog.toml",
               "[bake]\nroot_motion = \"in-place\"\n"
               "[animal.fish]\nmodel = \"assets/fish.glb\"\nstates = { swim = [\"swim\", \"walk\"] }\n"
               "[animal.bird]\nmodel = \"assets/bird.glb\"\nstates = { fly = [\"flap\"] }\n");
    write_text(TMP "/cmake-roster/CMakeLists.txt",
               "cmake_minimum_required(VERSION 3.20)\nproject(assets NONE)\nfind_package(crowdbake REQUIRED)\n"
               "crowdbake_bake_roster(roster catalog.toml OUTPUT_DIR palettes OPTIONS -j 2)\n");
    static char out[65536];
    if (sh(out, sizeof out, "cmake -G Ninja -S %s -B %s/build -DCMAKE_PREFIX_PATH=%s", dir, dir, prefix) != 0)
        fail_msg("%s", out);
    ninja_build(dir, true);
    const char *fish = TMP "/cmake-roster/build/palettes/fish.pal", *bird = TMP "/cmake-roster/build/palettes/bird.pal";
    const char *manifest = TMP "/cmake-roster/build/palettes/roster.json";
    struct timespec fish0 = mtime(fish), bird0 = mtime(bird);
    ninja_build(dir, false); /* nothing changed: nothing runs */
    /* The fish's model changes (a four-legged fish now): only its palette is baked again. */
    snprintf(cmd, sizeof cmd, "cp %s/quadruped.glb %s/assets/fish.glb", samples_dir(), dir);
    assert_int_equal(system(cmd), 0);
    ninja_build(dir, true);
    if (same_time(mtime(fish), fish0)) fail_msg("fish.pal was not baked again after its model changed");
    if (!same_time(mtime(bird), bird0)) fail_msg("bird.pal was rewritten, though its model did not change");
    char *json = read_whole_file(manifest, NULL);
    if (!strstr(json, "\"clip\": \"walk\"")) fail_msg("the manifest does not show the new fish:\n%s", json);
    free(json);
    ninja_build(dir, false);
}

/* On Debian 12's own Node.js 18 the tests stop before any runs, saying which Node.js they need
 * and the command that gets it (instead of every browser test failing in playwright-core). */
static void test_make_check_names_the_node_it_needs(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip(); /* a Makefile check: the normal build runs it */
    assert_int_equal(system("mkdir -p " TMP "/node18 && printf '#!/bin/sh\\necho v18.19.0\\n' > " TMP "/node18/node && "
                            "chmod +x " TMP "/node18/node"), 0);
    static char out[65536];
    assert_int_not_equal(sh(out, sizeof out, "PATH=%s/" TMP "/node18:$PATH make --no-print-directory check-node", root), 0);
    if (!strstr(out, "need Node.js 20 or newer") || !strstr(out, "this is Node.js 18.19.0") ||
        !strstr(out, "https://deb.nodesource.com/setup_20.x | bash - && apt-get install -y nodejs"))
        fail_msg("%s", out);
    assert_int_equal(sh(out, sizeof out, "make --no-print-directory check-node"), 0); /* this machine's own node */
}

/* Whether `text` holds `word` with no letter, digit or '-' right before or after it. */
static bool has_word(const char *text, const char *word)
{
    size_t n = strlen(word);
    for (const char *p = strstr(text, word); p; p = strstr(p + 1, word)) {
        char before = p > text ? p[-1] : ' ', after = p[n];
        bool edge_before = !(isalnum((unsigned char)before) || before == '-');
        bool edge_after = !(isalnum((unsigned char)after) || after == '-');
        if (edge_before && edge_after) return true;
    }
    return false;
}

/* The man page renders without a warning; both completions offer every option of every
 * command's own option table. */
static void test_man_page_and_completions(void **state)
{
    (void)state;
    if (skip_under_sanitizers()) skip();
    static char out[65536];
    assert_int_equal(sh(out, sizeof out, "groff -man -ww -z docs/crowdbake.1"), 0);
    if (out[0]) fail_msg("docs/crowdbake.1: %s", out);
    char *bash = read_whole_file("completions/crowdbake.bash", NULL), *zsh = read_whole_file("completions/_crowdbake", NULL);
    static const char *const sources[] = {"cli/cmd_bake.c",   "cli/cmd_info.c",   "cli/cmd_inspect.c",
                                          "cli/cmd_preview.c", "cli/cmd_report.c", "cli/cmd_sample.c",
                                          "cli/cmd_vat.c",     "cli/cmd_verify.c", "cli/cmd_mesh.c",
                                          "cli/cmd_view.c",    "cli/cmd_roster.c",  "cli/cli.c"};
    int options = 0;
    for (size_t i = 0; i < COUNT_OF(sources); ++i) {
        char *src = read_whole_file(sources[i], NULL);
        for (char *p = strstr(src, "{\"-"); p; p = strstr(p + 1, "{\"-")) {
            char name[64] = "";
            sscanf(p + 2, "%63[-a-z]", name);
            bool in_bash = has_word(bash, name), in_zsh = has_word(zsh, name);
            if (!in_bash || !in_zsh) fail_msg("%s: option %s is missing from the %s completion", sources[i], name,
                                              in_bash ? "zsh" : "bash");
            options++;
        }
        free(src);
    }
    assert_true(options > 60);
    free(bash), free(zsh);
    /* And bash really completes them. */
    assert_int_equal(sh(out, sizeof out, "bash -c \". completions/crowdbake.bash; COMP_WORDS=(crowdbake bake --roo); "
                                         "COMP_CWORD=2; _crowdbake; echo \\${COMPREPLY[@]}\""), 0);
    if (strcmp(out, "--root-motion\n") != 0) fail_msg("bash completion of 'bake --roo': %s", out);
}

/* Whether `inc` (as written between the quotes) names one of the tool's own headers: beside
 * `file`, or under cli/ (its -I). */
static bool tool_header(const char *file, const char *inc, size_t len)
{
    char path[PATH_MAX];
    const char *slash = strrchr(file, '/');
    snprintf(path, sizeof path, "%.*s/%.*s", (int)(slash - file), file, (int)len, inc);
    if (exists(path) && strstr(path, "/../") == NULL) return true;
    snprintf(path, sizeof path, "cli/%.*s", (int)len, inc);
    return exists(path) && strstr(path, "/../") == NULL;
}

/* Whether `inc` names a header of the internal tier (src/internal/X.h, as "internal/X.h"). */
static bool internal_header(const char *inc, size_t len)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "src/%.*s", (int)len, inc);
    return strncmp(inc, "internal/", 9) == 0 && memchr(inc + 9, '/', len - 9) == NULL && exists(path);
}

/* The command is a client of the library: its files (cli/) include the installed headers
 * (crowdbake/X.h, the reader crowdbake_pal.h), the internal tier's plumbing (internal/X.h:
 * src/internal, linked from libcrowdbake.a, not exported) and the tool's own, never a header
 * private to src/core, src/bake or formats/; and the public headers include only each other. */
static void test_tool_uses_only_the_public_headers(void **state)
{
    (void)state;
    static char out[1 << 17];
    assert_int_equal(sh(out, sizeof out, "grep -H \"^#include \\\"\" cli/*.c cli/*.h cli/*/*.c cli/*/*.cpp cli/*/*.h include/crowdbake/*.h"),
                     0);
    int lines = 0;
    for (char *line = strtok(out, "\n"); line; line = strtok(NULL, "\n"), ++lines) {
        *strchr(line, ':') = '\0';
        const char *file = line, *inc = strstr(line + strlen(line) + 1, "#include \"") + 10;
        size_t len = (size_t)(strchr(inc, '"') - inc);
        bool tool = strncmp(file, "cli/", 4) == 0;
        bool ok = tool ? strncmp(inc, "crowdbake/", 10) == 0 || strncmp(inc, "crowdbake_pal.h\"", 16) == 0 ||
                             internal_header(inc, len) || tool_header(file, inc, len)
                       : memchr(inc, '/', len) == NULL;
        if (!ok) fail_msg("%s: #include \"%.*s\" is not a public header", file, (int)len, inc);
    }
    assert_true(lines > 60);
}

/* The Godot addon's zip (make godot-addon) is the same bytes from any build directory and holds
 * every file of runtimes/godot/addons/crowdbake under addons/crowdbake, to unpack into a project's folder. */
static void test_godot_addon_zip(void **state)
{
    (void)state;
    static char out[65536];
    if (sh(out, sizeof out,
           "make --no-print-directory BUILD=" TMP "/zip1 godot-addon && make --no-print-directory BUILD=" TMP
           "/zip2 godot-addon && cmp " TMP "/zip1/crowdbake-godot-addon.zip " TMP "/zip2/crowdbake-godot-addon.zip") != 0)
        fail_msg("%s", out);
    if (sh(out, sizeof out,
           "cd runtimes/godot && find addons/crowdbake -type f | LC_ALL=C sort > ../../" TMP "/zip1/want && cd ../.. && unzip -Z1 " TMP
           "/zip1/crowdbake-godot-addon.zip | LC_ALL=C sort | diff " TMP "/zip1/want -") != 0)
        fail_msg("the zip's files differ from runtimes/godot/addons/crowdbake:\n%s", out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_destdir_layout),
        cmocka_unit_test(test_shared_library_exports_only_its_api),
        cmocka_unit_test(test_pkg_config_program_bakes_fox),
        cmocka_unit_test(test_tool_links_against_the_installed_library),
        cmocka_unit_test(test_cmake_program_bakes_fox),
        cmocka_unit_test_teardown(test_installed_view_serves_the_viewer, stop_server),
        cmocka_unit_test(test_cmake_roster_rebakes_only_what_changed),
        cmocka_unit_test(test_make_check_names_the_node_it_needs),
        cmocka_unit_test(test_man_page_and_completions),
        cmocka_unit_test(test_tool_uses_only_the_public_headers),
        cmocka_unit_test(test_godot_addon_zip),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
