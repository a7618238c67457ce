/* test_catalog.c - the animal catalog: validation messages with line numbers, state keywords,
 * speed references, characters outside ASCII, the manifest against its schema, shared rigs,
 * LOD remapping, incremental and parallel bakes, the depfile, a failing type that does not
 * stop the others, a missing model's exit code, the log's order and sizes, and types of one plan
 * key planned once yet baking what each bakes alone. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "catalog/catalog_toml.h"
#include "roster/roster.h"

#define TMP TEST_TMP "/catalog"

static char samples_abs[512];

static int setup(void **state)
{
    (void)state;
    char full[PATH_MAX];
    if (!realpath(samples_dir(), full) || strlen(full) >= sizeof samples_abs) return -1;
    memcpy(samples_abs, full, strlen(full) + 1);
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* A catalog over the samples; `extra` is appended verbatim. Returns its path. */
static const char *catalog(const char *name, const char *out_dir, const char *extra)
{
    static char path[PATH_MAX];
    static char text[16384];
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"%s\"\nfps = 30\n\n"
             "[animal.goat]\nmodel = \"%s/quadruped.glb\"\nlods = [\"%s/quadruped_lod1.glb\"]\n"
             "states = { idle = [\"idle\"], wander = [\"walk\"], flee = [\"gallop\", \"run\"] }\ndefault_state = \"wander\"\n\n"
             "[animal.sheep]\nmodel = \"%s/quadruped.glb\"\nstates = { rest = [\"idle\"], walk = [\"walk\"], run = [\"run\"] }\n\n"
             "[animal.fish]\nmodel = \"%s/fish.glb\"\nstates = { swim = [\"SWIM\"] }\n%s",
             out_dir, samples_abs, samples_abs, samples_abs, samples_abs, extra);
    snprintf(path, sizeof path, TMP "/%s.toml", name);
    write_text(path, text);
    return path;
}

static void expect_catalog_error(const char *text, const char *needle, unsigned line)
{
    char path[] = TMP "/bad.toml";
    write_text(path, text);
    cb_catalog cat;
    cb_error err = {0};
    if (cb_catalog_load(path, &cat, &err) == CB_OK) {
        cb_catalog_free(&cat);
        fail_msg("accepted a catalog that should fail with '%s'", needle);
    }
    assert_int_equal(err.status, CB_ERR_INPUT);
    char where[64];
    snprintf(where, sizeof where, "bad.toml:%u:", line);
    if (!strstr(err.message, needle) || !strstr(err.message, where))
        fail_msg("message '%s' lacks '%s' or '%s'", err.message, needle, where);
}

static void test_validation_errors_name_line_and_fix(void **state)
{
    (void)state;
    char model[640], text[2048];
    snprintf(model, sizeof model, "model = \"%s/fish.glb\"", samples_abs);
    snprintf(text, sizeof text, "[animal.fish]\n%s\nspeed_refrence = 2\n", model);
    expect_catalog_error(text, "unknown key 'speed_refrence'; did you mean 'speed_reference'?", 3);
    snprintf(text, sizeof text, "[bak]\nfps = 30\n[animal.fish]\n%s\n", model);
    expect_catalog_error(text, "unknown key 'bak'; did you mean 'bake'?", 1);
    snprintf(text, sizeof text, "[animal.fish]\n%s\nfps = \"fast\"\n", model);
    expect_catalog_error(text, "fps must be a rate in frames per second or \"auto\"", 3);
    snprintf(text, sizeof text, "[animal.fish]\n%s\nstates = { swim = [\"swim\"] }\ndefault_state = \"fly\"\n", model);
    expect_catalog_error(text, "default_state 'fly' is not one of its states (swim)", 4);
    snprintf(text, sizeof text, "[animal.fish]\n%s\n\n[animal.fish]\n%s\n", model, model);
    expect_catalog_error(text, "fish", 4); /* TOML: a table defined twice */
    snprintf(text, sizeof text, "[animal.Fish]\n%s\n[animal.fish]\n%s\n", model, model);
    expect_catalog_error(text, "differ only in case", 3);
    snprintf(text, sizeof text, "[animal.fish]\n%s\nclips = [\"swim\", { source = \"swim\" }]\n", model);
    expect_catalog_error(text, "two clips are named 'swim'", 3);
    expect_catalog_error("[animal.fish\nmodel = 1\n", "", 1); /* TOML syntax */
    snprintf(text, sizeof text, "[budget]\nvram = \"lots\"\n[animal.fish]\n%s\n", model);
    expect_catalog_error(text, "vram must be a size", 2);
}

/* Characters outside ASCII: accepted where TOML allows them (comments, and every kind of
 * string: one with escaped quotes, a literal one, a multi-line one ending in two more quotes),
 * refused with their place anywhere else. There toml++ 3.3 would reach undefined behaviour
 * (UBSan: "execution reached an unreachable program point"), so they never get to it. */
static void test_non_ascii_only_in_strings_and_comments(void **state)
{
    (void)state;
    char text[2048], path[] = TMP "/utf8.toml";
    snprintf(text, sizeof text,
             "# la vache \xc3\xa9\n"
             "[animal.fish] # poisson \xc2\xa1\n"
             "model = '%s/fish.glb'\n"
             "states = { \"nage \\\"\xc3\xa9\\\"\" = [\"swim\", '\xc2\xa1', \"\"\"\xe3\x80\x81\"\"\"\"\"] }\n",
             samples_abs);
    write_text(path, text);
    cb_catalog cat;
    cb_error err = {0};
    if (cb_catalog_load(path, &cat, &err) != CB_OK) fail_msg("refused: %s", err.message);
    assert_int_equal(cat.animal_count, 1);
    assert_int_equal(cat.animals[0].state_count, 1);
    const cb_catalog_state *st = &cat.animals[0].states[0];
    assert_string_equal(st->name, "nage \"\xc3\xa9\"");
    assert_int_equal(st->keyword_count, 3);
    assert_string_equal(st->keywords[1], "\xc2\xa1");
    assert_string_equal(st->keywords[2], "\xe3\x80\x81\"\""); /* the two quotes before the closing three */
    cb_catalog_free(&cat);
    snprintf(text, sizeof text, "[animal.fish]\nmodel = '%s/fish.glb'\nfps =\xc2\xa1 30\n", samples_abs);
    expect_catalog_error(text, "bad.toml:3:6: a non-ASCII character outside any quoted string or comment", 3);
    expect_catalog_error("[animal.fish]\n\xc2\xa1 = 1\n", "bad.toml:2:1: a non-ASCII character", 2);
    expect_catalog_error("[animal.fish]\nmodel = \"x\" \xe3\x80\x80# ideographic space\n", "bad.toml:2:13:", 2);
}

/* Errors only the models can reveal come from the bake, still with the catalog's position. */
static void test_state_and_clip_errors_list_what_exists(void **state)
{
    (void)state;
    char text[2048];
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"out-err\"\n[animal.bird]\nmodel = \"%s/bird.glb\"\nstates = { fly = [\"flap\"], flee = "
             "[\"gallop\", \"sprint\"] }\n[animal.fish]\nmodel = \"%s/fish.glb\"\nclips = [\"swim\", \"jump\"]\n",
             samples_abs, samples_abs);
    write_text(TMP "/errors.toml", text);
    cb_catalog cat;
    cb_error err = {0};
    assert_int_equal(cb_catalog_load(TMP "/errors.toml", &cat, &err), CB_OK);
    cb_roster r;
    cb_roster_options opt = {0};
    opt.jobs = 2;
    assert_int_equal(cb_roster_bake(&cat, &opt, &r, &err), CB_ERR_INPUT);
    assert_int_equal(r.failed, 2);
    const char *bird = r.types[0].error.message, *fish = r.types[1].error.message;
    if (!strstr(bird, "errors.toml:5:") || !strstr(bird, "state 'flee' matches no clip") || !strstr(bird, "flap, glide"))
        fail_msg("bird: %s", bird);
    if (!strstr(fish, "errors.toml:8:") || !strstr(fish, "clips: no clip 'jump'; the clips are: swim")) fail_msg("fish: %s", fish);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

/* A type with states bakes the clips they play and extra_clips, and says what it left out; a
 * catalog's clip names match as --clip's do (Cow's clips are "AnimalArmature|NAME"). */
static void test_a_catalog_bakes_the_clips_its_states_play(void **state)
{
    (void)state;
    char cow[PATH_MAX], rel[PATH_MAX], text[3 * PATH_MAX + 1024];
    shared_path(rel, sizeof rel, "assets/quaternius-cow/Cow.glb");
    assert_non_null(realpath(rel, cow));
    const char *states = "states = { idle = [\"idle\"], walk = [\"walk\"], run = [\"gallop\"], graze = [\"eating\"] }\n";
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"out-used\"\nfps = 30\n[animal.a]\nmodel = \"%s\"\n%s[animal.b]\nmodel = \"%s\"\n%s"
             "extra_clips = [\"death\"]\n[animal.c]\nmodel = \"%s\"\nclips = [\"Walk\", { source = \"idle\", name = \"rest\" }]\n",
             cow, states, cow, states, cow);
    write_text(TMP "/used.toml", text);
    cb_catalog cat;
    cb_error err = {0};
    assert_int_equal(cb_catalog_load(TMP "/used.toml", &cat, &err), CB_OK);
    cb_roster r;
    cb_roster_options opt = {.jobs = 1};
    assert_int_equal(cb_roster_bake(&cat, &opt, &r, &err), CB_OK);
    const cb_roster_type *a = &r.types[0], *b = &r.types[1], *c = &r.types[2];
    /* Cow at 30 fps: Eating 180 frames, Gallop 19, Idle 100, Walk 31 (info), in file order */
    assert_int_equal(a->clip_count, 4);
    assert_string_equal(a->clips[0].name, "AnimalArmature|Eating");
    assert_string_equal(a->clips[3].name, "AnimalArmature|Walk");
    assert_int_equal(a->clips[0].frames + a->clips[1].frames + a->clips[2].frames + a->clips[3].frames, a->rows);
    bool noted = false;
    for (uint32_t i = 0; i < a->warnings.count; ++i)
        noted |= strstr(a->warnings.items[i].message, "baked 4 of 12 clips") &&
                 strstr(a->warnings.items[i].message, "AnimalArmature|Attack_Kick") &&
                 strstr(a->warnings.items[i].message, "extra_clips = [\"Attack_Headbutt\", \"Attack_Kick\"");
    assert_true(noted);
    assert_int_equal(b->clip_count, 5); /* Death joins them, in the model's order */
    assert_string_equal(b->clips[0].name, "AnimalArmature|Death");
    assert_int_equal(c->clip_count, 2);
    assert_string_equal(c->clips[0].name, "AnimalArmature|Walk");
    assert_string_equal(c->clips[1].name, "rest");
    cb_roster_free(&r);
    cb_catalog_free(&cat);

    char *at = strstr(text, "\"Walk\"");
    memcpy(at, "\"Wakl\"", 6);
    write_text(TMP "/used.toml", text);
    assert_int_equal(cb_catalog_load(TMP "/used.toml", &cat, &err), CB_OK);
    assert_int_equal(cb_roster_bake(&cat, &opt, &r, &err), CB_ERR_INPUT);
    if (!strstr(r.types[2].error.message, "used.toml:13:") ||
        !strstr(r.types[2].error.message, "clips: no clip 'Wakl'; did you mean 'AnimalArmature|Walk'?"))
        fail_msg("c: %s", r.types[2].error.message);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

static void test_state_keyword_matching(void **state)
{
    (void)state;
    const char *clips[] = {"Idle_Breathe", "Walk", "Run_Fast", "Gallop", "Attack_Bite"};
    const char *flee[] = {"run", "gallop"}, *attack[] = {"attack", "bite"}, *none[] = {"swim"}, *later[] = {"fly", "GALLOP"};
    assert_int_equal(cb_match_state(clips, 5, flee, 2), 2);   /* keywords in order: run first */
    assert_int_equal(cb_match_state(clips, 5, attack, 2), 4);
    assert_int_equal(cb_match_state(clips, 5, none, 1), -1);
    assert_int_equal(cb_match_state(clips, 5, later, 2), 3); /* case-insensitive, second keyword */
}

static double clip_speed(const char *model_path, const char *clip_name, const char **method)
{
    cb_ground_speed gs;
    cb_model *m = load_or_fail(model_path);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info;
    assert_int_equal(cb_clip_analyze(s, cb_model_find_animation(m, clip_name), 30, -1, NULL, &info, &err), CB_OK);
    cb_measure_ground_speed(s, &info, &gs);
    *method = gs.method;
    double v = gs.speed;
    cb_sampler_free(s);
    cb_model_free(m);
    return v;
}

static void test_speed_reference_auto(void **state)
{
    (void)state;
    char q[600], fox[1024];
    snprintf(q, sizeof q, "%s/quadruped.glb", samples_abs);
    const char *method;
    /* The generator moves the root at 1.2 and 4.0 m/s: the root-motion measurement must say so. */
    assert_float_equal(clip_speed(q, "walk", &method), 1.2, 1e-6);
    assert_string_equal(method, "root motion");
    assert_float_equal(clip_speed(q, "run", &method), 4.0, 1e-6);
    assert_float_equal(clip_speed(q, "idle", &method), 0, 0);
    /* Fox walks and runs in place: the speed comes from its planted feet. */
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    double walk = clip_speed(fox, "Walk", &method);
    assert_string_equal(method, "planted feet");
    double run = clip_speed(fox, "Run", &method);
    printf("  Fox: Walk %.1f units/s, Run %.1f units/s (planted feet)\n", walk, run);
    assert_true(walk > 0 && run > 1.5 * walk);
    assert_float_equal(clip_speed(fox, "Survey", &method), 0, 1e-9); /* standing still */
}

static int run_cli(const char *args, char *out, size_t size)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s %s 2>&1", crowdbake_exe(), args);
    return run_command(cmd, out, size);
}

static void test_manifest_sharing_and_lods(void **state)
{
    (void)state;
    static char out[65536];
    char args[2048];
    const char *path = catalog("roster", "out-roster", "");
    snprintf(args, sizeof args, "bake %s -q", path);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    /* The manifest against its schema (ajv, draft 2020-12). */
    require_node_validators();
    assert_int_equal(run_command("node tests/tools/validator/validate_schema.mjs docs/roster.schema.json " TMP
                                 "/out-roster/roster.json 2>&1", out, sizeof out), 0);
    /* goat and sheep share one palette: only goat.pal exists. */
    struct stat st;
    assert_int_equal(stat(TMP "/out-roster/goat.pal", &st), 0);
    assert_int_not_equal(stat(TMP "/out-roster/sheep.pal", &st), 0);
    snprintf(args, sizeof args, "python3 -c \"import json; t = json.load(open('%s/out-roster/roster.json'))['types']; "
             "print(t['sheep']['shares_palette_of'], t['sheep']['palette'], t['goat']['states']['flee']['clip'], "
             "t['fish']['states']['swim']['instance']['phase'], json.dumps(t['goat']['lods'][0]['joint_remap']))\"", TMP);
    assert_int_equal(run_command(args, out, sizeof out), 0);
    char owner[64], pal[64], flee[64], phase[64];
    assert_int_equal(sscanf(out, "%63s %63s %63s %63s", owner, pal, flee, phase), 4);
    assert_string_equal(owner, "goat");
    assert_string_equal(pal, "goat.pal");
    assert_string_equal(flee, "run"); /* "gallop" matches nothing, "run" does */
    assert_string_equal(phase, "golden_ratio");
    /* The LOD remap, checked against the joint names of both files. */
    char q[600], l[600];
    snprintf(q, sizeof q, "%s/quadruped.glb", samples_abs);
    snprintf(l, sizeof l, "%s/quadruped_lod1.glb", samples_abs);
    cb_model *main = load_or_fail(q), *lod = load_or_fail(l);
    const char *p = strchr(out, '[');
    assert_non_null(p);
    for (uint32_t j = 0; j < lod->skins[0].joint_count; ++j) {
        unsigned k = (unsigned)strtoul(p + 1, (char **)&p, 10);
        assert_string_equal(lod->nodes[lod->skins[0].joints[j]].name, main->nodes[main->skins[0].joints[k]].name);
    }
    assert_true(lod->skins[0].joint_count < main->skins[0].joint_count);
    cb_model_free(main);
    cb_model_free(lod);
}

static void test_incompatible_lod_names_the_joint(void **state)
{
    (void)state;
    char text[2048];
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out-lod\"\n[animal.goat]\nmodel = \"%s/quadruped.glb\"\n"
             "lods = [\"%s/fish.glb\"]\n", samples_abs, samples_abs);
    write_text(TMP "/lod.toml", text);
    char out[4096];
    assert_int_equal(run_cli("bake " TMP "/lod.toml -q", out, sizeof out), EXIT_INPUT);
    /* The fish's first joints are "root" (same bind pose) then "spine0" (another one). */
    if (!strstr(out, "lod.toml:5:") || !strstr(out, "LOD joint 'spine0' has another bind pose")) fail_msg("%s", out);
}

static long long mtime_ns(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) return -1;
    return (long long)st.st_mtim.tv_sec * 1000000000LL + st.st_mtim.tv_nsec;
}

static void test_incremental_second_run_rewrites_nothing(void **state)
{
    (void)state;
    static char out[65536];
    /* fish2 uses its own copy of the fish model, so changing it touches one type only. */
    char extra[1024], cmd[2048];
    snprintf(cmd, sizeof cmd, "cp %s/fish.glb " TMP "/fish-copy.glb", samples_abs);
    assert_int_equal(system(cmd), 0);
    snprintf(extra, sizeof extra, "\n[animal.fish2]\nmodel = \"fish-copy.glb\"\nfps = 20\n"); /* not shared with fish */
    const char *path = catalog("incr", "out-incr", extra);
    char args[2048];
    snprintf(args, sizeof args, "bake %s --json", path);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    const char *files[] = {TMP "/out-incr/goat.pal", TMP "/out-incr/fish.pal", TMP "/out-incr/fish2.pal", TMP "/out-incr/roster.json"};
    long long before[3];
    /* Palettes dated in 2001: a rewrite would give them today's time, however fast it runs. The
     * manifest's date is the bake's to move (past its inputs, for Make); a rewrite of it would be
     * a new file renamed over it, so its inode tells. */
    for (int i = 0; i < 3; ++i) {
        const struct timespec old[2] = {{978307200, 0}, {978307200, 0}};
        assert_int_equal(utimensat(AT_FDCWD, files[i], old, 0), 0);
        before[i] = mtime_ns(files[i]);
    }
    struct stat manifest;
    assert_int_equal(stat(files[3], &manifest), 0);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"baked\": 0"));
    assert_non_null(strstr(out, "\"up_to_date\": 3"));
    for (int i = 0; i < 3; ++i) assert_true(mtime_ns(files[i]) == before[i]);
    struct stat manifest_now;
    assert_int_equal(stat(files[3], &manifest_now), 0);
    assert_true(manifest_now.st_ino == manifest.st_ino);
    /* A different model in fish2's file: only fish2 is baked again. */
    snprintf(cmd, sizeof cmd, "cp %s/bird.glb " TMP "/fish-copy.glb", samples_abs);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"baked\": 1"));
    assert_non_null(strstr(out, "\"name\": \"fish2\",\n      \"outcome\": \"baked\""));
    assert_true(mtime_ns(files[0]) == before[0] && mtime_ns(files[1]) == before[1]);
    assert_true(mtime_ns(files[2]) != before[2]);
    /* A palette torn after its rename (power loss: outputs are not fsync'ed) fails its checksum
     * and is baked again rather than trusted. */
    FILE *torn = fopen(files[0], "r+b");
    assert_non_null(torn);
    assert_int_equal(fseek(torn, -1, SEEK_END), 0);
    int last = fgetc(torn);
    assert_int_equal(fseek(torn, -1, SEEK_END), 0);
    fputc(last ^ 0x5a, torn);
    fclose(torn);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"baked\": 1"));
    assert_non_null(strstr(out, "\"name\": \"goat\",\n      \"outcome\": \"baked\""));
    /* --force bakes everything again. */
    snprintf(args, sizeof args, "bake %s --json --force", path);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"baked\": 3"));
}

static void test_parallel_bake_is_byte_identical(void **state)
{
    (void)state;
    char out[8192], args[2048];
    char bird[700];
    snprintf(bird, sizeof bird, "\n[animal.bird]\nmodel = \"%s/bird.glb\"\nfps = 24\n", samples_abs);
    char p1[1024], p4[1024];
    snprintf(p1, sizeof p1, "%s", catalog("par1", "out-j1", bird));
    snprintf(p4, sizeof p4, "%s", catalog("par4", "out-j4", bird));
    snprintf(args, sizeof args, "bake %s -j 1 -q --force", p1);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    snprintf(args, sizeof args, "bake %s -j 4 -q --force", p4);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    const char *names[] = {"goat.pal", "fish.pal", "bird.pal"};
    for (int i = 0; i < 3; ++i) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "cmp " TMP "/out-j1/%s " TMP "/out-j4/%s", names[i], names[i]);
        assert_int_equal(system(cmd), 0);
    }
    /* The manifests differ only in the catalog's name. */
    assert_int_equal(system("grep -v catalog " TMP "/out-j1/roster.json > " TMP "/m1 && grep -v catalog " TMP
                            "/out-j4/roster.json > " TMP "/m4 && cmp " TMP "/m1 " TMP "/m4"), 0);
}

static void test_depfile_lists_every_input_of_every_output(void **state)
{
    (void)state;
    char out[8192], args[2048], fox[PATH_MAX], extra[PATH_MAX + 64];
    shared_path(args, sizeof args, "assets/derived-fox/separate");
    assert_non_null(realpath(args, fox));
    snprintf(extra, sizeof extra, "\n[animal.fox]\nmodel = \"%s/Fox.gltf\"\n", fox);
    const char *path = catalog("dep", "out-dep", extra);
    snprintf(args, sizeof args, "bake %s -q --depfile " TMP "/out-dep.d", path);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    FILE *f = fopen(TMP "/out-dep.d", "r");
    assert_non_null(f);
    static char dep[16384];
    size_t n = fread(dep, 1, sizeof dep - 1, f);
    dep[n] = '\0';
    fclose(f);
    /* goat.pal depends on the catalog, the tool, the quadruped (goat and sheep), and the goat's LOD. */
    static char expect[16384];
    char tool[PATH_MAX];
    assert_non_null(realpath(crowdbake_exe(), tool));
    snprintf(expect, sizeof expect, TMP "/out-dep/goat.pal: " TMP "/dep.toml \\\n  %s \\\n  %s/quadruped.glb \\\n  "
             "%s/quadruped_lod1.glb \\\n  %s/quadruped.glb\n", tool, samples_abs, samples_abs, samples_abs);
    if (!strstr(dep, expect)) fail_msg("depfile:\n%s\nlacks:\n%s", dep, expect);
    snprintf(expect, sizeof expect, TMP "/out-dep/fish.pal: " TMP "/dep.toml \\\n  %s \\\n  %s/fish.glb\n", tool, samples_abs);
    assert_non_null(strstr(dep, expect));
    /* A .gltf's external buffer is an input too (editing Fox.bin must re-bake); its image,
     * never read, is not. */
    snprintf(expect, sizeof expect, TMP "/out-dep/fox.pal: " TMP "/dep.toml \\\n  %s \\\n  %s/Fox.gltf \\\n  %s/Fox.bin\n",
             tool, fox, fox);
    if (!strstr(dep, expect)) fail_msg("depfile:\n%s\nlacks:\n%s", dep, expect);
    assert_non_null(strstr(dep, TMP "/out-dep/roster.json: " TMP "/dep.toml"));
    assert_null(strstr(dep, "sheep.pal")); /* sheep writes no file of its own */
}

static void test_a_failing_type_does_not_stop_the_others(void **state)
{
    (void)state;
    char out[8192], args[2048], cmd[1024];
    snprintf(cmd, sizeof cmd, "head -c 1000 %s/bird.glb > " TMP "/broken.glb", samples_abs);
    assert_int_equal(system(cmd), 0);
    const char *path = catalog("fail", "out-fail", "\n[animal.broken]\nmodel = \"broken.glb\"\n");
    snprintf(args, sizeof args, "bake %s", path);
    assert_int_equal(run_cli(args, out, sizeof out), EXIT_INPUT);
    if (!strstr(out, "broken           FAILED: ") || !strstr(out, "truncated GLB") || !strstr(out, "2 baked"))
        fail_msg("%s", out);
    struct stat st;
    assert_int_equal(stat(TMP "/out-fail/goat.pal", &st), 0);
    assert_int_equal(stat(TMP "/out-fail/fish.pal", &st), 0);
    assert_int_not_equal(stat(TMP "/out-fail/broken.pal", &st), 0);
    assert_int_equal(system("ls -a " TMP "/out-fail | grep -q '\\.tmp\\.'"), 256); /* no temporaries left */
    /* Every type failed: no sizes of nothing ("0 types in 0 palettes ... 0.0x") after the log. */
    write_text(TMP "/allfail.toml", "[bake]\nout_dir = \"out-allfail\"\n[animal.broken]\nmodel = \"broken.glb\"\n");
    assert_int_equal(run_cli("bake " TMP "/allfail.toml", out, sizeof out), EXIT_INPUT);
    if (!strstr(out, "0 baked, 0 up to date, 0 sharing a palette, 1 failed") || strstr(out, "0 types") || strstr(out, "0.0x") ||
        strstr(out, "Roster:"))
        fail_msg("%s", out);
}

/* A missing model is a file that cannot be read (EXIT_IO), named on the command line or by a
 * catalog (whose bake said EXIT_INPUT, as for a catalog that is wrong); a missing LOD too. Nothing
 * is written. */
static void test_a_missing_model_exits_as_on_the_command_line(void **state)
{
    (void)state;
    char out[8192], args[2048];
    assert_int_equal(run_cli("bake " TMP "/nope/missing.glb -o " TMP "/missing.pal", out, sizeof out), EXIT_IO);
    assert_non_null(strstr(out, "crowdbake: " TMP "/nope/missing.glb: cannot read: No such file or directory"));
    write_text(TMP "/missing.toml", "[bake]\nout_dir = \"out-missing\"\n[animal.fish]\nmodel = \"nope/missing.glb\"\n");
    assert_int_equal(run_cli("bake " TMP "/missing.toml", out, sizeof out), EXIT_IO);
    if (!strstr(out, "crowdbake: " TMP "/missing.toml:4:9: [animal.fish] model file " TMP "/nope/missing.glb does not exist"))
        fail_msg("%s", out);
    assert_int_equal(run_cli("report " TMP "/missing.toml", out, sizeof out), EXIT_IO);
    snprintf(args, sizeof args, "[bake]\nout_dir = \"out-missing\"\n[animal.fish]\nmodel = \"%s/fish.glb\"\nlods = [\"nope/lod.glb\"]\n",
             samples_abs);
    write_text(TMP "/missing-lod.toml", args);
    assert_int_equal(run_cli("bake " TMP "/missing-lod.toml", out, sizeof out), EXIT_IO);
    assert_non_null(strstr(out, "missing-lod.toml:5:9: [animal.fish] LOD file " TMP "/nope/lod.glb does not exist"));
    assert_int_equal(system("test ! -e " TMP "/missing.pal && test ! -e " TMP "/out-missing"), 0);
}

/* The log lists the types in catalog order, the order of the manifest, whatever order the
 * threads finish in: here the Cow (../shared, 744 rows, first by name and the longest, so the
 * threads start it first and it finishes last) before three short types. Each baked line gives
 * the sizes `bake MODEL` gives for the same palette, labelled: the texture as uploaded and the
 * file (they said 59.6 KiB and 63.6 KiB for the same Fox palette). */
static void test_the_log_is_in_catalog_order_with_the_sizes_of_bake_model(void **state)
{
    (void)state;
    static char out[16384];
    char args[4 * PATH_MAX], fox[PATH_MAX], cow[PATH_MAX], fox_abs[PATH_MAX], cow_abs[PATH_MAX], expect[128];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    assert_non_null(realpath(fox, fox_abs)), assert_non_null(realpath(cow, cow_abs)); /* the catalog is in TMP */
    snprintf(args, sizeof args, "[bake]\nout_dir = \"out-order\"\nfps = 30\n[animal.acow]\nmodel = \"%s\"\n"
             "[animal.bfish]\nmodel = \"%s/fish.glb\"\n[animal.cbird]\nmodel = \"%s/bird.glb\"\n"
             "[animal.dfox]\nmodel = \"%s\"\n", cow_abs, samples_abs, samples_abs, fox_abs);
    write_text(TMP "/order.toml", args);
    assert_int_equal(run_cli("bake " TMP "/order.toml -j 4 --force", out, sizeof out), 0);
    const char *names[] = {"  acow ", "  bfish ", "  cbird ", "  dfox "}, *at = out;
    for (size_t i = 0; i < COUNT_OF(names); ++i)
        if (!(at = strstr(at, names[i]))) fail_msg("'%s' not after the types before it in:\n%s", names[i], out);
    /* Fox: 24 bones x 2 texels x 159 rows x 8 bytes (qpos/u16); the file as written. */
    struct stat st;
    assert_int_equal(stat(TMP "/out-order/dfox.pal", &st), 0);
    snprintf(expect, sizeof expect, "(%.1f KiB texture, %.1f KiB file, 48x159,", 24 * 2 * 159 * 8 / 1024.0, st.st_size / 1024.0);
    if (!strstr(out, expect)) fail_msg("expected '%s' in:\n%s", expect, out);
    snprintf(args, sizeof args, "bake %s -o " TMP "/fox-alone.pal --fps 30", fox);
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    snprintf(expect, sizeof expect, "fox-alone.pal: %.1f KiB texture, %.1f KiB file, 48x159 texels", 24 * 2 * 159 * 8 / 1024.0,
             st.st_size / 1024.0);
    if (!strstr(out, expect)) fail_msg("expected '%s' in:\n%s", expect, out);
}

/* Types whose plan keys are equal (the same model bytes, here under two file names, the same
 * clips and settings) are planned once and the others copy the plan (roster_plans.c): what the
 * one-step bake writes must be what each type baked in a process of its own (`--type`, which
 * plans alone) merges to, byte for byte; a type with another fps plans its own. */
static void test_types_of_one_plan_bake_what_each_bakes_alone(void **state)
{
    (void)state;
    char out[8192], args[4096], text[2048];
    assert_int_equal(system("mkdir -p " TMP "/plans"), 0);
    snprintf(args, sizeof args, "cp %s/quadruped.glb " TMP "/plans/a.glb && cp %s/quadruped.glb " TMP "/plans/b.glb",
             samples_abs, samples_abs);
    assert_int_equal(system(args), 0);
    snprintf(text, sizeof text, "[bake]\nout_dir = \"out\"\n\n[animal.a1]\nmodel = \"a.glb\"\n\n[animal.a2]\nmodel = "
             "\"b.glb\"\n\n[animal.a3]\nmodel = \"a.glb\"\nfps = 24\n\n[animal.a4]\nmodel = \"b.glb\"\n");
    write_text(TMP "/plans/catalog.toml", text);
    snprintf(args, sizeof args, "bake " TMP "/plans/catalog.toml -q -j 2");
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    const char *types[] = {"a1", "a2", "a3", "a4"};
    for (int i = 0; i < 4; ++i) {
        snprintf(args, sizeof args, "bake " TMP "/plans/catalog.toml --type %s --out-dir " TMP "/plans/alone -q -j 1",
                 types[i]);
        assert_int_equal(run_cli(args, out, sizeof out), 0);
    }
    snprintf(args, sizeof args, "roster merge -q -o " TMP "/plans/alone/roster.json " TMP "/plans/alone/a1.fragment " TMP
             "/plans/alone/a2.fragment " TMP "/plans/alone/a3.fragment " TMP "/plans/alone/a4.fragment");
    assert_int_equal(run_cli(args, out, sizeof out), 0);
    assert_int_equal(system("cmp " TMP "/plans/out/roster.json " TMP "/plans/alone/roster.json"), 0);
    assert_int_equal(system("cmp " TMP "/plans/out/a1.pal " TMP "/plans/alone/a1.pal"), 0);
    assert_int_equal(system("cmp " TMP "/plans/out/a3.pal " TMP "/plans/alone/a3.pal"), 0);
    assert_int_not_equal(system("cmp -s " TMP "/plans/out/a1.pal " TMP "/plans/out/a3.pal"), 0);
    /* a2 and a4 share a1's palette; a3 (24 fps) has its own. */
    assert_int_equal(run_command("grep -c '\"shares_palette_of\": \"a1\"' " TMP "/plans/out/roster.json", out, sizeof out), 0);
    assert_int_equal(atoi(out), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validation_errors_name_line_and_fix),
        cmocka_unit_test(test_non_ascii_only_in_strings_and_comments),
        cmocka_unit_test(test_state_and_clip_errors_list_what_exists),
        cmocka_unit_test(test_a_catalog_bakes_the_clips_its_states_play),
        cmocka_unit_test(test_state_keyword_matching),
        cmocka_unit_test(test_speed_reference_auto),
        cmocka_unit_test(test_manifest_sharing_and_lods),
        cmocka_unit_test(test_incompatible_lod_names_the_joint),
        cmocka_unit_test(test_incremental_second_run_rewrites_nothing),
        cmocka_unit_test(test_parallel_bake_is_byte_identical),
        cmocka_unit_test(test_depfile_lists_every_input_of_every_output),
        cmocka_unit_test(test_a_failing_type_does_not_stop_the_others),
        cmocka_unit_test(test_a_missing_model_exits_as_on_the_command_line),
        cmocka_unit_test(test_the_log_is_in_catalog_order_with_the_sizes_of_bake_model),
        cmocka_unit_test(test_types_of_one_plan_bake_what_each_bakes_alone),
    };
    return cmocka_run_group_tests_name("catalog", tests, setup, NULL);
}
