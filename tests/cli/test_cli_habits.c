/* test_cli_habits.c - the command's habits, as a user of gltfpack, ktx or toktx expects them:
 * --version/-V, `crowdbake help COMMAND`, `-o -` refused with a message (never a file named
 * "-"), a .fbx/.obj/.png/.blend named as what it is with the converters to use, and clip names
 * matched regardless of case and by a unique part, with "did you mean" for a miss and the
 * candidates for an ambiguity, the same in every command that takes clip names. The clip names
 * are the shared models' own (Fox: Survey, Walk, Run; the Cow: AnimalArmature|Gallop and
 * AnimalArmature|Gallop_Jump among others); and info's line per mesh node, one for a row of
 * nodes drawing the same mesh. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include "crowdbake/core.h"

#define TMP TEST_TMP "/cli_habits"

static char fox[PATH_MAX], cow[PATH_MAX];
static char out[1 << 16];

static int setup(void **state)
{
    (void)state;
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* Runs `crowdbake ARGS 2>&1` (printf-formatted); returns the exit code, the output in out. */
#define crowdbake(...) run_crowdbake(out, sizeof out, __VA_ARGS__)

static void assert_contains(const char *needle)
{
    if (!strstr(out, needle)) fail_msg("expected \"%s\" in:\n%s", needle, out);
}

static void test_version_and_help_command(void **state)
{
    (void)state;
    static const char *const version_flags[] = {"--version", "-V"};
    for (size_t i = 0; i < COUNT_OF(version_flags); ++i) {
        assert_int_equal(crowdbake("%s", version_flags[i]), 0);
        assert_string_equal(out, "crowdbake " CROWDBAKE_VERSION "\n");
    }
    /* `help COMMAND` is the command's --help, for every command. */
    static const char *const commands[] = {"info", "sample", "bake", "inspect", "verify", "preview", "mesh", "vat", "report", "view"};
    static char want[1 << 16];
    for (size_t i = 0; i < COUNT_OF(commands); ++i) {
        assert_int_equal(crowdbake("%s --help", commands[i]), 0);
        snprintf(want, sizeof want, "%s", out);
        assert_int_equal(crowdbake("help %s", commands[i]), 0);
        assert_string_equal(out, want);
        assert_non_null(strstr(out, "usage: crowdbake "));
    }
    assert_int_equal(crowdbake("help bkae"), EXIT_USAGE);
    assert_contains("unknown command 'bkae'; did you mean 'bake'?");
    assert_int_equal(crowdbake("help"), 0);
    assert_contains("crowdbake help COMMAND");
}

/* `-o -` is no file named "-": every command writing files says so and writes nothing. */
static void test_output_dash_is_refused(void **state)
{
    (void)state;
    char abs_fox[PATH_MAX];
    assert_non_null(realpath(fox, abs_fox));
    /* From inside TMP, so a file named "-" would land there. */
    char exe[PATH_MAX], cmd[3 * PATH_MAX];
    assert_non_null(realpath(crowdbake_exe(), exe));
    snprintf(cmd, sizeof cmd, "cd " TMP " && %s bake %s -o - 2>&1", exe, abs_fox);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_USAGE);
    struct stat st;
    assert_int_not_equal(stat(TMP "/-", &st), 0);
    static const char *const commands[][2] = {{"bake", "-o -"}, {"bake", "--output=-"}, {"vat", "-o -"}, {"mesh", "-o -"}};
    for (size_t i = 0; i < COUNT_OF(commands); ++i) {
        assert_int_equal(crowdbake("%s %s %s", commands[i][0], abs_fox, commands[i][1]), EXIT_USAGE);
        assert_contains(": writes no standard output");
        assert_contains("name a file, e.g. ");
        assert_int_equal(strchr(out, '\n'), out + strlen(out) - 1); /* one line */
    }
}

/* What artists export before glTF is named, by its first bytes or else its name, with the way
 * to convert it; never "not a valid glTF 2.0 file: Root element is not a JSON object". */
static void test_other_formats_are_named_with_their_converters(void **state)
{
    (void)state;
    write_text(TMP "/cow.fbx", "Kaydara FBX Binary  \x1a");
    write_text(TMP "/cow_ascii.fbx", "; FBX 7.4.0 project file\n");
    write_text(TMP "/fbx_named_model", "Kaydara FBX Binary  \x1a"); /* the bytes decide */
    write_text(TMP "/cow.obj", "# exported\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_text(TMP "/cow.blend", "BLENDER-v300RENDH");
    assert_int_equal(system("cp docs/viewer.png " TMP "/cow.png"), 0);
    static const char *const files[][2] = {{"cow.fbx", "(an FBX file)"}, {"cow_ascii.fbx", "(an FBX file (ASCII))"},
                                           {"fbx_named_model", "(an FBX file)"}, {"cow.obj", "(a Wavefront OBJ file)"},
                                           {"cow.blend", "(a Blender .blend file)"}, {"cow.png", "(a PNG image)"}};
    static const char *const commands[] = {"info", "bake", "sample --fps 10 --json", "vat"};
    for (size_t i = 0; i < COUNT_OF(files); ++i)
        for (size_t c = 0; c < COUNT_OF(commands); ++c) {
            bool writes = strncmp(commands[c], "bake", 4) == 0 || strncmp(commands[c], "vat", 3) == 0;
            assert_int_equal(crowdbake("%s " TMP "/%s%s", commands[c], files[i][0], writes ? " -o " TMP "/out.pal" : ""),
                             EXIT_INPUT);
            assert_contains(": not glTF ");
            assert_contains(files[i][1]);
            assert_contains("FBX2glTF");
            assert_contains("Blender");
            struct stat st;
            assert_int_not_equal(stat(TMP "/out.pal", &st), 0);
        }
    /* A real glTF with a surprising name is still read. */
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "cp %s " TMP "/fox.obj", fox);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(crowdbake("info " TMP "/fox.obj"), 0);
    assert_contains("3 clips");
}

/* crowdbake's own outputs and a catalog, given where a model is wanted, are named with what to give
 * instead (never "Root element is not a JSON object" for a .pal, nor a TOML error for one `report`
 * took for a catalog), exit 4, and nothing is written; a folder given as a catalog cannot be read. */
static void test_own_outputs_are_named_where_a_model_is_wanted(void **state)
{
    (void)state;
    assert_int_equal(crowdbake("bake %s -o " TMP "/own.pal -q", fox), 0);
    write_text(TMP "/roster.json", "{\n  \"schema\": \"crowdbake-roster/1\",\n  \"types\": {}\n}\n");
    write_text(TMP "/herd.toml", "[animal.fox]\nmodel = \"fox.glb\"\n");
    static const char *const files[][2] = {{"own.pal", "not a model but a crowdbake palette (.pal)"},
                                           {"roster.json", "not a model but a roster manifest"},
                                           {"herd.toml", "a catalog, not a model"}};
    static const char *const commands[] = {"info", "bake", "vat", "report"};
    for (size_t i = 0; i < COUNT_OF(files); ++i)
        for (size_t c = 0; c < COUNT_OF(commands); ++c) {
            bool catalog_reader = strcmp(commands[c], "bake") == 0 || strcmp(commands[c], "report") == 0;
            if (catalog_reader && i == 2) continue; /* they read catalogs */
            bool writes = strcmp(commands[c], "bake") == 0 || strcmp(commands[c], "vat") == 0;
            assert_int_equal(crowdbake("%s " TMP "/%s%s", commands[c], files[i][0], writes ? " -o " TMP "/out.pal" : ""),
                             EXIT_INPUT);
            assert_contains(files[i][1]);
            if (i == 0) assert_contains("'crowdbake inspect " TMP "/own.pal' shows what it holds");
            assert_int_equal(strchr(out, '\n'), out + strlen(out) - 1); /* one line */
            struct stat st;
            assert_int_not_equal(stat(TMP "/out.pal", &st), 0);
        }
    /* A folder where a catalog is wanted is unreadable, not an empty catalog ("lists no animals") */
    assert_int_equal(system("mkdir -p " TMP "/folder.toml"), 0);
    static const char *const folders[] = {"bake " TMP "/folder.toml", "report " TMP "/folder.toml", "report " TMP};
    for (size_t i = 0; i < COUNT_OF(folders); ++i) {
        assert_int_equal(crowdbake("%s", folders[i]), EXIT_IO);
        assert_contains(": cannot read: Is a directory");
    }
}

/* A bake's bytes, to compare two spellings of the same clips. */
static char *bake_bytes(const char *clips, size_t *n)
{
    assert_int_equal(crowdbake("bake %s -o " TMP "/clips.pal -q --clip %s", fox, clips), 0);
    return read_whole_file(TMP "/clips.pal", n);
}

static void test_clip_names_match_by_case_and_part(void **state)
{
    (void)state;
    /* Case and parts: the same palette as the exact names. */
    size_t na, nb;
    char *exact = bake_bytes("Walk,Run", &na), *loose = bake_bytes("walk,RUN", &nb);
    assert_true(na == nb && memcmp(exact, loose, na) == 0);
    free(loose);
    loose = bake_bytes("alk,ru", &nb);
    assert_true(na == nb && memcmp(exact, loose, na) == 0);
    free(exact), free(loose);
    /* The part after an exporter's "Armature|" picks that clip though a longer one holds it. */
    assert_int_equal(crowdbake("sample %s --fps 2 --json --clip gallop --frame 0", cow), 0);
    assert_contains("\"name\": \"AnimalArmature|Gallop\",");
    assert_int_equal(crowdbake("sample %s --fps 2 --json --clip GALLOP_jump --frame 0", cow), 0);
    assert_contains("\"name\": \"AnimalArmature|Gallop_Jump\",");
    /* An ambiguity lists the candidates; a miss says what was meant. */
    assert_int_equal(crowdbake("bake %s -o " TMP "/cow.pal --clip gall", cow), EXIT_USAGE);
    assert_contains("--clip gall: 'gall' matches 2 clips: 'AnimalArmature|Gallop', 'AnimalArmature|Gallop_Jump'; give more "
                    "of the name");
    assert_int_equal(crowdbake("bake %s -o " TMP "/fox.pal --clip wlak", fox), EXIT_USAGE);
    assert_contains("--clip wlak: no clip 'wlak'; did you mean 'Walk'?");
    assert_int_equal(crowdbake("vat %s -o " TMP "/cow.exr --clip galop", cow), EXIT_USAGE);
    assert_contains("no clip 'galop'; did you mean 'AnimalArmature|Gallop'?");
    assert_int_equal(crowdbake("bake %s -o " TMP "/fox.pal -q --loop survey --one-shot RUN", fox), 0);
    /* The same matcher for a palette's clips: inspect and verify. */
    assert_int_equal(crowdbake("bake %s -o " TMP "/fox.pal -q", fox), 0);
    assert_int_equal(crowdbake("inspect " TMP "/fox.pal --clip walk --frame 0 --json"), 0);
    assert_contains("\"clip\": \"Walk\"");
    assert_int_equal(crowdbake("inspect " TMP "/fox.pal --clip wak --frame 0"), EXIT_USAGE);
    assert_contains("no clip 'wak'; did you mean 'Walk'?");
    assert_int_equal(crowdbake("verify %s " TMP "/fox.pal --clip walk --random 2", fox), 0);
    assert_contains("  Walk ");
    assert_true(!strstr(out, "  Run ") && !strstr(out, "  Survey "));
    assert_int_equal(crowdbake("verify %s " TMP "/fox.pal --exclude-clip WALK --random 2", fox), 0);
    assert_true(strstr(out, "  Run ") && strstr(out, "  Survey ") && !strstr(out, "  Walk "));
    /* preview takes them as verify does. */
    assert_int_equal(crowdbake("preview %s " TMP "/fox.pal -o " TMP "/fox-walk.png --cell 32 --clip walk", fox), 0);
    assert_contains(": 1 clip x 6 frames (192x84 pixels): Walk (rows, top to bottom)");
    assert_int_equal(crowdbake("preview %s " TMP "/fox.pal -o " TMP "/fox-walk.png --cell 32 --clip wak", fox), EXIT_USAGE);
    assert_contains("--clip wak: no clip 'wak'; did you mean 'Walk'?");
    assert_int_equal(crowdbake("preview %s " TMP "/fox.pal -o " TMP "/fox-walk.png --cell 32 --exclude-clip walk", fox), 0);
    assert_contains(": 2 clips x 6 frames (192x138 pixels): Survey / Run (rows, top to bottom)");
    /* An error-bounded bake's header gives its clips' rates and fitted rows (Fox's local rows: Survey and Walk
     * at their 24 fps keys, Run on its keys through a map whose cells make 21.58 fps of rows, none fitted), not
     * the base 30; global rows: Survey 24 fps, Walk and Run chosen above it, one fitted. */
    assert_int_equal(crowdbake("inspect " TMP "/fox.pal"), 0);
    assert_contains("fps 21.5827-24 per clip, 0 of 3 clips fitted, speed reference 105.58 units/s");
    assert_int_equal(crowdbake("bake %s -o " TMP "/fox.pal -q --bone-space global", fox), 0);
    assert_int_equal(crowdbake("inspect " TMP "/fox.pal"), 0);
    assert_contains("fps 24-120 per clip, 1 of 3 clips fitted, speed reference 105.58 units/s");
    assert_true(!strstr(out, "fps 30,") && !strstr(out, " m/s"));
}

/* samples/catalog.toml copied to `toml`, baking into TMP/`out_dir` and its models from this build's samples. */
static void sample_catalog(const char *out_dir, const char *toml)
{
    char cwd[PATH_MAX], samples[PATH_MAX];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_non_null(realpath(samples_dir(), samples));
    assert_int_equal(run(NULL, 0, "sed -e 's|^out_dir = .*|out_dir = \"%s/" TMP "/%s\"|' -e 's|\"../build/samples/|\"%s/|' "
                         "samples/catalog.toml > %s", cwd, out_dir, samples, toml), 0);
}

/* report bakes for seconds: a line per type on stderr with -v (and on a terminal), none with
 * -q or when stderr is not a terminal; stdout keeps only the report, so --json still parses.
 * The types are samples/catalog.toml's (a copy baking into this test's folder). */
static void test_report_progress(void **state)
{
    (void)state;
    static char err[1 << 16];
    char cmd[4 * PATH_MAX];
    sample_catalog("roster", TMP "/catalog.toml");
    snprintf(cmd, sizeof cmd, "%s report " TMP "/catalog.toml --json -v 2>&1 >" TMP "/report.json", crowdbake_exe());
    assert_int_equal(run_command(cmd, err, sizeof err), 0);
    static const char *const types[] = {"  bird ", "  fish ", "  goat ", "  sheep "};
    for (size_t i = 0; i < COUNT_OF(types); ++i)
        if (!strstr(err, types[i])) fail_msg("no progress line for %s in:\n%s", types[i], err);
    assert_int_equal(system("python3 -c 'import json; json.load(open(\"" TMP "/report.json\"))'"), 0);
    static const char *const silent[] = {"--json", "--json -q", "--json -v --quiet"};
    for (size_t i = 0; i < COUNT_OF(silent); ++i) {
        snprintf(cmd, sizeof cmd, "%s report " TMP "/catalog.toml %s 2>&1 >/dev/null", crowdbake_exe(), silent[i]);
        assert_int_equal(run_command(cmd, err, sizeof err), 0);
        assert_string_equal(err, "");
    }
}

/* -q on the commands that print a summary of what they wrote: nothing printed, the file written. */
static void test_quiet_writes_without_a_summary(void **state)
{
    (void)state;
    assert_int_equal(crowdbake("bake %s -o " TMP "/q.pal -q", fox), 0);
    static const char *const commands[][2] = {{"vat %s -o " TMP "/q.exr", TMP "/q.exr"},
                                              {"mesh %s -o " TMP "/q.glb", TMP "/q.glb"},
                                              {"preview %s " TMP "/q.pal -o " TMP "/q.png", TMP "/q.png"}};
    char args[1024];
    for (size_t i = 0; i < COUNT_OF(commands); ++i)
        for (int quiet = 0; quiet < 3; ++quiet) {
            unlink(commands[i][1]);
            snprintf(args, sizeof args, commands[i][0], fox);
            assert_int_equal(crowdbake("%s%s", args, quiet == 0 ? "" : quiet == 1 ? " -q" : " --quiet"), 0);
            struct stat st;
            assert_int_equal(stat(commands[i][1], &st), 0);
            if (quiet) assert_string_equal(out, "");
            else assert_int_equal(strncmp(out, commands[i][1], strlen(commands[i][1])), 0); /* "FILE: what it holds" */
        }
}

/* verify -q: nothing printed when it passes; over --max-error only the one line of why, exit 6. */
static void test_verify_quiet(void **state)
{
    (void)state;
    assert_int_equal(crowdbake("bake %s -o " TMP "/vq.pal -q", fox), 0);
    assert_int_equal(crowdbake("verify %s " TMP "/vq.pal --random 2 -q", fox), 0);
    assert_string_equal(out, "");
    assert_int_equal(crowdbake("verify %s " TMP "/vq.pal --random 2 --quiet --max-error 0.0001", fox), EXIT_VERIFY);
    assert_contains("is over --max-error 0.0001");
    assert_int_equal(strchr(out, '\n'), out + strlen(out) - 1);
}

/* info -q: the description without the warnings a bake would give. Magnum's animation.glb has
 * an empty clip and a channel with no keys (MANIFEST.md: deliberately invalid). */
static void test_info_quiet(void **state)
{
    (void)state;
    char model[PATH_MAX], cmd[2 * PATH_MAX];
    shared_path(model, sizeof model, "assets/magnum-animation/animation.glb");
    snprintf(cmd, sizeof cmd, "%s info %s 2>&1 >/dev/null", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_contains("crowdbake: warning: ");
    assert_contains("clip 'empty' has no channels");
    snprintf(cmd, sizeof cmd, "%s info %s -q 2>&1 >/dev/null", crowdbake_exe(), model);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_string_equal(out, "");
    assert_int_equal(crowdbake("info %s --quiet", model), 0);
    assert_contains("clip ");
}

/* A .ktx2 from bake is read by inspect and verify like the .pal beside it (test_ktx2 compares
 * their outputs). */
static void test_ktx2_is_read(void **state)
{
    (void)state;
    assert_int_equal(crowdbake("bake %s -o " TMP "/k.pal --format pal,ktx2 --precision half -q", fox), 0);
    assert_int_equal(crowdbake("inspect " TMP "/k.ktx2"), 0);
    assert_contains("k.ktx2: KTX2 palette, qpos/half, 24 bones x 2 texels");
    assert_int_equal(crowdbake("verify %s " TMP "/k.ktx2 --random 2 -q", fox), 0);
    assert_string_equal(out, "");
}

/* Runs `crowdbake ARGS` with stdout thrown away; its stderr in out, its exit code returned. */
static int crowdbake_stderr(const char *args)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s %.3000s 2>&1 >/dev/null", crowdbake_exe(), args);
    return run_command(cmd, out, sizeof out);
}

/* -q and -v on every command: -v says on stderr what was read (and written) and how long it
 * took; -q leaves stderr empty (here, on inputs without warnings); both: -q wins. Each command's
 * --help lists both. view serves until stopped: it is run on a missing file, which must fail on
 * the file, not on the options. */
static void test_quiet_and_verbose_everywhere(void **state)
{
    (void)state;
    assert_int_equal(crowdbake("bake %s -o " TMP "/qv.pal -q", fox), 0);
    static const char *const runs[][2] = {
        {"info %s", NULL},
        {"sample %s --fps 5 --json --clip walk --frame 0", NULL},
        {"bake %s -o " TMP "/qv2.pal", TMP "/qv2.pal"},
        {"inspect " TMP "/qv.pal", NULL},
        {"verify %s " TMP "/qv.pal --random 2", NULL},
        {"preview %s " TMP "/qv.pal -o " TMP "/qv.png --cell 32 --columns 2", TMP "/qv.png"},
        {"mesh %s -o " TMP "/qv.glb", TMP "/qv.glb"},
        {"vat %s -o " TMP "/qv.exr", TMP "/qv.exr"},
        {"report %s", NULL},
    };
    char args[2048], with[2200], read_line[PATH_MAX + 32];
    for (size_t i = 0; i < COUNT_OF(runs); ++i) {
        snprintf(args, sizeof args, runs[i][0], fox);
        const char *first = strchr(args, ' ') + 1; /* the first file the command reads */
        snprintf(read_line, sizeof read_line, "crowdbake: read %.*s in ", (int)strcspn(first, " "), first);
        snprintf(with, sizeof with, "%s -v", args);
        assert_int_equal(crowdbake_stderr(with), 0);
        if (strncmp(args, "report", 6) == 0) assert_contains("  Fox "); /* its per-type line */
        else if (!strstr(out, read_line)) fail_msg("'%s': no \"%s\" in:\n%s", with, read_line, out);
        if (runs[i][1] && strncmp(args, "bake", 4) == 0) assert_contains("crowdbake: wrote " TMP "/qv2.pal (");
        else if (runs[i][1]) assert_contains(runs[i][1]);
        for (int k = 0; k < 3; ++k) {
            snprintf(with, sizeof with, "%s %s", args, k == 0 ? "-q" : k == 1 ? "--quiet" : "-v --quiet");
            assert_int_equal(crowdbake_stderr(with), 0);
            if (out[0]) fail_msg("'%s' printed on stderr:\n%s", with, out);
        }
    }
    static const char *const commands[] = {"info", "sample", "bake", "inspect", "verify", "preview", "mesh", "vat", "report", "view"};
    for (size_t i = 0; i < COUNT_OF(commands); ++i) {
        assert_int_equal(crowdbake("%s --help", commands[i]), 0);
        assert_contains("-q, --quiet");
        assert_contains("-v, --verbose");
        assert_int_not_equal(crowdbake("%s " TMP "/missing.glb -v -q", commands[i]), 0);
        if (strstr(out, "unknown option")) fail_msg("%s -v -q: %s", commands[i], out);
    }
}

/* A catalog's bake: with -v a progress line per type on stderr as each is done, whatever
 * order they finish in, and --json on stdout still one JSON document; none with -q. */
static void test_catalog_bake_progress(void **state)
{
    (void)state;
    char cmd[4 * PATH_MAX];
    sample_catalog("progress", TMP "/progress.toml");
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/progress.toml --force --json -v 2>&1 >" TMP "/bake.json", crowdbake_exe());
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    /* samples/catalog.toml: bird, fish and goat baked, sheep sharing goat's palette */
    static const char *const lines[] = {"] bird: baked ", "] fish: baked ", "] goat: baked ", "] sheep: shares goat's palette\n"};
    for (size_t i = 0; i < COUNT_OF(lines); ++i)
        if (!strstr(out, lines[i])) fail_msg("no progress line \"%s\" in:\n%s", lines[i], out);
    for (int n = 1; n <= 4; ++n) {
        char counted[32];
        snprintf(counted, sizeof counted, "crowdbake: [%d/4] ", n);
        assert_contains(counted);
    }
    assert_int_equal(system("python3 -c 'import json; json.load(open(\"" TMP "/bake.json\"))'"), 0);
    /* The goat's death has its own budget (max_error = 2): the note gives the range, not the bake's 1 alone. */
    assert_int_equal(run_command("grep -c 'error-bounded (max_error 1-2 mm/m, per clip)' " TMP "/bake.json", NULL, 0), 0);
    static const char *const silent[] = {"--json", "--json -q", "-q", "--json -v -q"};
    for (size_t i = 0; i < COUNT_OF(silent); ++i) {
        snprintf(cmd, sizeof cmd, "bake " TMP "/progress.toml --force %s", silent[i]);
        assert_int_equal(crowdbake_stderr(cmd), 0);
        if (out[0]) fail_msg("'%s' printed on stderr:\n%s", cmd, out);
    }
}

/* The completions know `help COMMAND` and --version. */
static void test_completions_know_help_and_version(void **state)
{
    (void)state;
    assert_int_equal(run_command("bash -c '. completions/crowdbake.bash; COMP_WORDS=(crowdbake help ba); COMP_CWORD=2; "
                                 "_crowdbake; echo ${COMPREPLY[@]}; COMP_WORDS=(crowdbake --v); COMP_CWORD=1; _crowdbake; "
                                 "echo ${COMPREPLY[@]}'", out, sizeof out), 0);
    assert_string_equal(out, "bake\n--version\n");
    char *zsh = read_whole_file("completions/_crowdbake", NULL);
    assert_non_null(strstr(zsh, "{-V,--version}"));
    assert_non_null(strstr(zsh, "  help)"));
    free(zsh);
}

static int count_lines_with(const char *text, const char *part)
{
    int n = 0;
    for (const char *p = strstr(text, part); p; p = strstr(p + 1, part)) ++n;
    return n;
}

/* info: a line per mesh node, not per primitive, and one for nodes drawing the same mesh. The
 * counts are MANIFEST.md's: the robot has 14 skinned mesh nodes sharing one skin, the Cow 7
 * primitives on one skinned mesh node. */
static void test_info_folds_primitives_and_instances(void **state)
{
    (void)state;
    char robot[PATH_MAX], simple[PATH_MAX], cmd[4 * PATH_MAX];
    shared_path(robot, sizeof robot, "assets/robot-quaternius-raylib/robot.glb");
    assert_int_equal(crowdbake("info %s", robot), 0);
    assert_int_equal(count_lines_with(out, "  mesh node "), 14);
    assert_int_equal(crowdbake("info %s", cow), 0);
    assert_int_equal(count_lines_with(out, "  mesh node"), 1);
    assert_contains("  mesh node 'Cow' (node 58): 7 primitives, ");
    /* SimpleSkin's one mesh drawn by twelve nodes (a herd placed in the file): one line. */
    shared_path(simple, sizeof simple, "assets/simpleskin-bevy/SimpleSkin.gltf");
    snprintf(cmd, sizeof cmd, "python3 -c \"import json,sys; g=json.load(open(sys.argv[1])); "
             "g['nodes'] += [{'name': 'copy%%d' %% i, 'mesh': 0, 'skin': 0} for i in range(11)]; "
             "g['scenes'][0]['nodes'] += list(range(3, 14)); json.dump(g, open(sys.argv[2], 'w'))\" %s " TMP "/herd.gltf", simple);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(crowdbake("info " TMP "/herd.gltf"), 0);
    assert_int_equal(count_lines_with(out, "  mesh node"), 1);
    assert_contains("  mesh nodes '");
    assert_contains(" .. 'copy10' (nodes 0 .. 13: 12 nodes, one mesh): each ");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_version_and_help_command),
        cmocka_unit_test(test_output_dash_is_refused),
        cmocka_unit_test(test_other_formats_are_named_with_their_converters),
        cmocka_unit_test(test_own_outputs_are_named_where_a_model_is_wanted),
        cmocka_unit_test(test_clip_names_match_by_case_and_part),
        cmocka_unit_test(test_info_folds_primitives_and_instances),
        cmocka_unit_test(test_report_progress),
        cmocka_unit_test(test_quiet_writes_without_a_summary),
        cmocka_unit_test(test_verify_quiet),
        cmocka_unit_test(test_info_quiet),
        cmocka_unit_test(test_ktx2_is_read),
        cmocka_unit_test(test_quiet_and_verbose_everywhere),
        cmocka_unit_test(test_catalog_bake_progress),
        cmocka_unit_test(test_completions_know_help_and_version),
    };
    return cmocka_run_group_tests_name("cli_habits", tests, setup, NULL);
}
