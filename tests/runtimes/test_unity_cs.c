/* test_unity_cs.c - the Unity package's C# (runtimes/unity), proven without the Unity Editor: its
 * engine-free core compiles with Debian's mcs and runs under mono, and what it reads equals the C
 * reader (include/crowdbake_pal.h) on Fox and Cow in every layout x precision, and Python's json on
 * the Cow roster; its herd's matrices, cross-fades, speed changes and footsteps equal what the C
 * reader gives for the same instance numbers; the Unity-facing code compiles against stubs of the
 * Unity API it calls (tests/runtimes/unity/stubs, each signature as Unity documents it); the herd's bone
 * pass (its compute kernel and the shaders' CB_BONE_TEXTURE variant) compiles with glslang and validates,
 * its kernel runs on Mesa's lavapipe (Vulkan) equal to the C runtime, and its rule and layout
 * (Runtime/Core/BonePass.cs) take the WebGL2 runtime's thresholds and decisions. No Unity Editor runs
 * here: nothing of this is drawn by Unity. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#include "crowdbake_pal.h"
#include "runtimes/bone_order.h"
#include "runtimes/conformance.h"
#include "runtimes/hlsl_harness.h"
#include "runtimes/timed_roster.h"
#include "timed_subset.h"

#define TMP TEST_TMP "/unity_cs"
#define CHECK_EXE TMP "/CrowdbakeCheck.exe"
#define PKG "runtimes/unity"

VKC_TEST_DEVICE("the Unity bone pass kernel")

static void run_or_fail(const char *cmd)
{
    static char log[16384];
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s:\n%s", cmd, log);
}

/* mcs and mono: DEB_PACKAGES installs them (mono-mcs, mono-runtime). */
static void build_check(void)
{
    static int built;
    if (built) return;
    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && mcs -warnaserror -nologo -out:%s tests/runtimes/unity/CrowdbakeCheck.cs %s/Runtime/Core/*.cs 2>&1",
             TMP, CHECK_EXE, PKG);
    run_or_fail(cmd);
    built = 1;
}

static void check_close(const char *what, double got, double want, double tol, double *worst)
{
    double d = fabs(got - want) / fmax(1.0, fabs(want));
    if (d > *worst) *worst = d;
    if (!(d <= tol)) fail_msg("%s: C# %.9g, C %.9g (relative difference %.3g > %.3g)", what, got, want, d, tol);
}

/* mono CrowdbakeCheck.exe ARGS > OUT */
static FILE *run_check(const char *args, const char *out)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "mono %s %s > %s 2>&1", CHECK_EXE, args, out);
    run_or_fail(cmd);
    FILE *f = fopen(out, "r");
    assert_non_null(f);
    return f;
}

/* Header, clips, bones and every bone's matrix at 11 times of every clip: C# against cbpal. */
static double compare_pal(const char *pal_path, unsigned *matrices)
{
    cbpal_file pal;
    char err[256], args[1024], line[8192];
    if (cbpal_open(pal_path, CBPAL_VERIFY_CHECKSUM, &pal, err, sizeof err)) fail_msg("%s", err);
    snprintf(args, sizeof args, "pal %s", pal_path);
    FILE *f = run_check(args, TMP "/pal.txt");
    double worst = 0;
    unsigned header = 0, clips = 0, bones = 0, offsets = 0, travelled = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'H') {
            unsigned v, fl, lay, prec, bc, rows, w, h, blocks, cc;
            unsigned long long sum;
            float fps, range, maxe, height, vis;
            assert_int_equal(sscanf(line, "H %u %u %u %u %u %u %u %u %u %u %f %f %f %f %f %llu", &v, &fl, &lay, &prec, &bc, &rows, &w,
                                    &h, &blocks, &cc, &fps, &range, &maxe, &height, &vis, &sum), 16);
            const cbpal_header *x = &pal.header;
            assert_true(v == x->version && fl == x->flags && lay == x->layout && prec == x->precision && bc == x->bone_count &&
                        rows == x->rows && w == x->width && h == x->height && blocks == x->blocks && cc == x->clip_count);
            assert_true(fps == x->fps && range == x->linear_range && maxe == x->max_error && height == x->model_height &&
                        vis == x->visible_error && sum == x->checksum);
            ++header;
        } else if (line[0] == 'C') {
            unsigned i, first, frames, flags;
            float fps, dur, start, lo, hi;
            cbpal_clip c;
            assert_int_equal(sscanf(line, "C %u %u %u %u %f %f %f %f %f", &i, &first, &frames, &flags, &fps, &dur, &start, &lo, &hi), 9);
            assert_int_equal(cbpal_get_clip(&pal, i, &c), 0);
            assert_true(first == c.first_row && frames == c.frames && flags == c.flags && fps == c.fps && dur == c.duration &&
                        start == c.start && lo == c.bounds_min[1] && hi == c.bounds_max[1]);
            ++clips;
        } else if (line[0] == 'B') {
            unsigned j;
            int parent;
            float b[6];
            cbpal_bone bone;
            assert_int_equal(sscanf(line, "B %u %d %f %f %f %f %f %f", &j, &parent, &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]), 8);
            assert_int_equal(cbpal_get_bone(&pal, j, &bone), 0);
            assert_int_equal(parent, bone.parent);
            for (int k = 0; k < 3; ++k) assert_true(b[k] == bone.bind_position[k] && b[3 + k] == bone.position_offset[k]);
            ++bones;
        } else if (line[0] == 'M') {
            unsigned clip, bone;
            double t;
            float m[16], want[16];
            char *p = line + 2;
            clip = (unsigned)strtoul(p, &p, 10);
            t = strtod(p, &p);
            bone = (unsigned)strtoul(p, &p, 10);
            for (int k = 0; k < 16; ++k) m[k] = strtof(p, &p);
            assert_int_equal(cbpal_bone_matrix(&pal, clip, t, bone, want), 0);
            for (int k = 0; k < 16; ++k) check_close("bone matrix", m[k], want[k], 1e-6, &worst);
            ++*matrices;
        } else if (line[0] == 'T') { /* the per-row travel offset, version 5 */
            unsigned clip;
            double t;
            float o[3], want[3];
            assert_int_equal(sscanf(line, "T %u %lf %f %f %f", &clip, &t, &o[0], &o[1], &o[2]), 5);
            assert_int_equal(cbpal_travel_offset(&pal, clip, t, want), 0);
            for (int k = 0; k < 3; ++k) check_close("travel offset", o[k], want[k], 1e-6, &worst);
            travelled += want[0] != 0 || want[2] != 0;
            ++offsets;
        } else {
            fail_msg("%s: unexpected line from CrowdbakeCheck: %s", pal_path, line);
        }
    }
    fclose(f);
    assert_int_equal(header, 1);
    assert_int_equal(clips, pal.header.clip_count);
    assert_int_equal(bones, pal.header.bone_count);
    assert_int_equal(*matrices, pal.header.clip_count * 11 * pal.header.bone_count);
    assert_int_equal(offsets, pal.header.clip_count * 11);
    if (pal.header.travel_table_offset && !travelled) fail_msg("%s: no travel offset read from its table", pal_path);
    if (pal.header.travel_table_offset) printf("  %u travel offsets (version 5), %u of them moving\n", offsets, travelled);
    cbpal_close(&pal);
    return worst;
}

static unsigned char *timed_fox_bytes(const char *fox, size_t *size);

static void test_reader_equals_the_c_reader(void **state)
{
    (void)state;
    build_check();
    const char *models[] = {"assets/fox-bevy/Fox.glb", "assets/quaternius-cow/Cow.glb"};
    const char *layouts[] = {"mat4", "affine", "qpos"}, *precisions[] = {"float", "half", "u16"};
    char model[1024], cmd[4096];
    for (int m = 0; m < 2; ++m) {
        shared_path(model, sizeof model, models[m]);
        for (int l = 0; l < 3; ++l)
            for (int p = 0; p < 3; ++p) {
                snprintf(cmd, sizeof cmd, "%s bake %s -o %s/x.pal --layout %s --precision %s -q 2>&1", crowdbake_exe(), model, TMP,
                         layouts[l], precisions[p]);
                run_or_fail(cmd);
                unsigned matrices = 0;
                double worst = compare_pal(TMP "/x.pal", &matrices);
                printf("  %s %s/%s: %u bone matrices, worst relative difference C# vs C %.3g\n", models[m] + 7, layouts[l],
                       precisions[p], matrices, worst);
            }
        for (int p = 0; p < 3; p += 2) { /* local rows (.pal version 6): each bone composed down its chain */
            snprintf(cmd, sizeof cmd, "%s bake %s -o %s/x.pal --bone-space local --layout qpos --precision %s -q 2>&1", crowdbake_exe(),
                     model, TMP, precisions[p]);
            run_or_fail(cmd);
            unsigned matrices = 0;
            double worst = compare_pal(TMP "/x.pal", &matrices);
            printf("  %s local qpos/%s: %u composed bone matrices, worst relative difference C# vs C %.3g\n", models[m] + 7,
                   precisions[p], matrices, worst);
        }
    }
    /* timed rows (.pal version 7): Fox's Walk and Run through their maps, C# InstanceFrame against cbpal_bone_matrix */
    size_t size;
    shared_path(model, sizeof model, models[0]);
    free(timed_fox_bytes(model, &size));
    unsigned matrices = 0;
    double worst = compare_pal(TMP "/timed-fox.pal", &matrices);
    printf("  fox-bevy/Fox.glb timed (half, 2 of 3 clips): %u bone matrices, worst relative difference C# vs C %.3g\n", matrices, worst);
}

/* Each damaged copy of `good` (a byte of each poke flipped low, then high; three cuts): the C#
 * reader's verdict equals cbpal_open_memory's, word for word, checksum verified and not. Returns how
 * many the tables' checks refused. */
static unsigned compare_verdicts(const unsigned char *good, size_t size, const size_t *pokes, size_t npokes, unsigned *compared)
{
    char line[1024], want[600], err[512];
    unsigned char *bad = malloc(size);
    assert_non_null(bad);
    unsigned refused = 0;
    for (size_t i = 0; i < npokes * 2 + 3; ++i) {
        size_t len = size;
        memcpy(bad, good, size);
        if (i < npokes * 2) bad[pokes[i / 2] + (i % 2 ? 3 : 0)] ^= i % 2 ? 0x80 : 0x01;
        else len = i == npokes * 2 ? 100 : i == npokes * 2 + 1 ? 4096 : size - 1;
        FILE *f = fopen(TMP "/bad.pal", "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(bad, 1, len, f), len);
        fclose(f);
        FILE *out = run_check("bad " TMP "/bad.pal", TMP "/bad.txt");
        for (unsigned flags = CBPAL_VERIFY_CHECKSUM;; flags = 0) {
            cbpal_file pal;
            if (cbpal_open_memory(bad, len, flags, &pal, err, sizeof err) == 0) {
                snprintf(want, sizeof want, "ok");
                cbpal_close(&pal);
            } else {
                snprintf(want, sizeof want, "x.pal: %s", err);
            }
            assert_non_null(fgets(line, sizeof line, out));
            line[strcspn(line, "\n")] = 0;
            if (strcmp(line, want) != 0) fail_msg("damage %zu (checksum %s): C# says '%s', C says '%s'", i, flags ? "on" : "off", line, want);
            refused += strcmp(want, "ok") != 0 && !strstr(want, "checksum");
            if (!flags) break;
        }
        fclose(out);
        ++*compared;
    }
    free(bad);
    return refused;
}

static unsigned char *bake_bytes(const char *model, const char *options, size_t *size)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/v.pal %s -q 2>&1", crowdbake_exe(), model, TMP, options);
    run_or_fail(cmd);
    unsigned char *bytes = (unsigned char *)read_whole_file(TMP "/v.pal", size);
    assert_non_null(bytes);
    return bytes;
}

static uint64_t le64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = v << 8 | p[i];
    return v;
}

/* Damaged files: the same verdict as cbpal_open_memory, word for word; zstd is refused with the fix;
 * and a local-rows file (.pal version 6) damaged in its flags, its range table's offset and entries,
 * and its parents. */
/* Fox (half) with Walk and Run made timed (tests/timed_subset.h), written by the library's writer: the file's bytes. */
static unsigned char *timed_fox_bytes(const char *fox, size_t *size)
{
    char cmd[4096], err[256];
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/uniform.pal --precision half --fps 30 -q 2>&1", crowdbake_exe(), fox, TMP);
    run_or_fail(cmd);
    cbpal_file uniform;
    cb_palette view, timed;
    cb_error e = {0};
    if (cbpal_open(TMP "/uniform.pal", CBPAL_VERIFY_CHECKSUM, &uniform, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(cb_palette_view(&uniform, &view, &e), CB_OK);
    assert_true(timed_subset_make(&uniform, &view, 0, 0, &timed));
    cb_model *m = load_or_fail(fox);
    if (timed_subset_write(TMP "/timed-fox.pal", &timed, &uniform, m, &e)) fail_msg("%s", e.message);
    cb_model_free(m);
    timed_subset_free(&timed);
    cb_palette_view_free(&view);
    cbpal_close(&uniform);
    unsigned char *bytes = (unsigned char *)read_whole_file(TMP "/timed-fox.pal", size);
    assert_non_null(bytes);
    assert_int_equal((uint32_t)le64(bytes + 8), 7);
    return bytes;
}

static void test_reader_verdicts_match(void **state)
{
    (void)state;
    build_check();
    char fox[1024], cmd[4096], line[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    size_t size;
    unsigned char *good = bake_bytes(fox, "--layout qpos --precision half", &size);
    /* offsets into the header and the first clip and bone entries, and lengths to cut the file to */
    const size_t pokes[] = {0, 8, 16, 20, 24, 28, 32, 36, 40, 44, 48, 52, 56, 60, 120, 128, 136, 144, 152, 160, 168, 176, 184, 256 + 8,
                            256 + 12, 256 + 4};
    unsigned compared = 0, refused = compare_verdicts(good, size, pokes, COUNT_OF(pokes), &compared);
    free(good);
    good = bake_bytes(fox, "--bone-space local --layout qpos --precision u16", &size);
    assert_true(good[12] & 32); /* flag bit 5 */
    size_t ranges = (size_t)le64(good + 200), bones = (size_t)le64(good + 128);
    const size_t local[] = {8, 20, 24, 200, 204, bones + 8, bones + 32 + 8, ranges, ranges + 12, ranges + 16, ranges + 28,
                            ranges + 32 + 4, ranges + 32 + 24};
    unsigned local_compared = 0, local_refused = compare_verdicts(good, size, local, COUNT_OF(local), &local_compared);
    free(good);
    /* timed rows (.pal version 7, tests/timed_subset.h): the flags, the table's offset and entries, the clips' flags, a map texel */
    size_t timed_size;
    unsigned char *timed = timed_fox_bytes(fox, &timed_size);
    size_t table = (size_t)le64(timed + 208), clips = (size_t)le64(timed + 120);
    uint32_t map_row = (uint32_t)le64(timed + clips + 80 + 8) - (uint32_t)le64(timed + table + 16 + 8); /* Walk's first map row */
    uint32_t height = (uint32_t)le64(timed + 48), width = (uint32_t)le64(timed + 44), row_texels = (uint32_t)le64(timed + 36);
    size_t map = (size_t)le64(timed + 152) + ((size_t)(map_row % height) * width + (map_row / height) * row_texels) * 8 + 8; /* cell 1 */
    const size_t timed_pokes[] = {8, 208, 212, clips + 28, clips + 80 + 28, table, table + 4, table + 8, table + 12, table + 16,
                                  table + 19, table + 24, table + 28, map, map + 1, map + 5};
    unsigned timed_compared = 0, timed_refused = compare_verdicts(timed, timed_size, timed_pokes, COUNT_OF(timed_pokes), &timed_compared);
    free(timed);
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/z.pal --zstd -q 2>&1", crowdbake_exe(), fox, TMP);
    run_or_fail(cmd);
    FILE *out = run_check("bad " TMP "/z.pal", TMP "/bad.txt");
    assert_non_null(fgets(line, sizeof line, out));
    fclose(out);
    if (!strstr(line, "zstd-compressed") || !strstr(line, "without --zstd")) fail_msg("zstd palette: %s", line);
    printf("  %u damaged files: C# and C give the same verdicts, checksum verified and not (%u refused by the tables' checks); "
           "local rows: %u damaged, %u refused; timed rows: %u damaged, %u refused; zstd refused: %s", compared, refused,
           local_compared, local_refused, timed_compared, timed_refused, line);
    assert_true(refused >= 20 && local_refused >= 10 && timed_refused >= 10);
}

/* A catalog bake of Cow into TMP/DIR with the [bake] keys KEYS: what a Unity roster import needs. */
static void bake_cow_into(const char *dir, const char *keys)
{
    char path[1024], bake_keys[512];
    snprintf(path, sizeof path, TMP "/%s.toml", dir);
    snprintf(bake_keys, sizeof bake_keys, "out_dir = \"%s\"\n%s", dir, keys);
    run_or_fail("mkdir -p " TMP);
    if (bake_cow_catalog(path, bake_keys,
                         "states = { idle = [\"idle\"], wander = [\"walk\"], flee = [\"gallop\"], die = [\"death\"] }\n"
                         "default_state = \"wander\""))
        fail_msg("%s did not bake", path);
}

/* The Cow catalog bake, once. */
static void bake_cow_roster(void)
{
    static int baked;
    if (!baked) bake_cow_into("roster", "");
    baked = 1;
}

/* Compares two files of space-separated tokens: numbers within tol (relative), words equal. */
static unsigned compare_token_files(const char *got_path, const char *want_path, double tol)
{
    FILE *got = fopen(got_path, "r"), *want = fopen(want_path, "r");
    assert_non_null(got);
    assert_non_null(want);
    char a[8192], b[8192];
    unsigned lines = 0;
    double worst = 0;
    while (fgets(b, sizeof b, want)) {
        if (!fgets(a, sizeof a, got)) fail_msg("C# stops before: %s", b);
        char *sa, *sb, *ta = strtok_r(a, " \n", &sa), *tb = strtok_r(b, " \n", &sb);
        for (; ta && tb; ta = strtok_r(NULL, " \n", &sa), tb = strtok_r(NULL, " \n", &sb)) {
            char *ea, *eb;
            double x = strtod(ta, &ea), y = strtod(tb, &eb);
            if (*ea || *eb || ea == ta) {
                if (strcmp(ta, tb) != 0) fail_msg("line %u: C# '%s', the manifest '%s'", lines + 1, ta, tb);
            } else {
                check_close("roster number", x, y, tol, &worst);
            }
        }
        if (ta || tb) fail_msg("line %u: C# and the manifest have different fields", lines + 1);
        ++lines;
    }
    if (fgets(a, sizeof a, got)) fail_msg("C# prints more: %s", a);
    fclose(got);
    fclose(want);
    return lines;
}

/* Types, clips, contacts, states and sockets as the C# roster reads them, against Python's json. */
static void test_roster_equals_the_manifest(void **state)
{
    (void)state;
    build_check();
    bake_cow_roster();
    fclose(run_check("roster " TMP "/roster/roster.json", TMP "/roster_cs.txt"));
    run_or_fail("python3 tests/runtimes/unity/roster_lines.py " TMP "/roster/roster.json > " TMP "/roster_py.txt 2>&1");
    unsigned lines = compare_token_files(TMP "/roster_cs.txt", TMP "/roster_py.txt", 1e-7); /* floats in C# */
    char log[65536];
    assert_int_equal(run_command("grep -c '^K ' " TMP "/roster_py.txt; grep -c '^O ' " TMP "/roster_py.txt; grep -c '^S ' " TMP
                                 "/roster_py.txt", log, sizeof log), 0);
    unsigned contacts, sockets, states;
    assert_int_equal(sscanf(log, "%u %u %u", &contacts, &sockets, &states), 3);
    printf("  Cow roster: %u lines equal (%u contacts, %u sockets, %u states)\n", lines, contacts, sockets, states);
    assert_int_equal(sockets, 10); /* docs/roster.md: Cow has 10 (its IK pole targets are rig helpers, not sockets) */
    assert_int_equal(states, 4);
    assert_true(contacts >= 8);
}


/* The timed catalog's roster (tests/runtimes/timed_roster.h) through Roster.Parse, equal to Python's json (timed_rows
 * included), and HerdState.InstanceData's numbers; a damaged timed state refused with one line. */
static void test_roster_timed_states(void **state)
{
    (void)state;
    build_check();
    bake_timed_roster(TMP);
    fclose(run_check("roster " TMP "/timed/roster.json", TMP "/timed_cs.txt"));
    run_or_fail("python3 tests/runtimes/unity/roster_lines.py " TMP "/timed/roster.json > " TMP "/timed_py.txt 2>&1");
    unsigned lines = compare_token_files(TMP "/timed_cs.txt", TMP "/timed_py.txt", 1e-7);
    char log[4096];
    assert_int_equal(run_command("grep -c '^R ' " TMP "/timed_py.txt", log, sizeof log), 0);
    printf("  timed catalog roster: %u lines equal, %d timed clips\n", lines, atoi(log));
    assert_true(atoi(log) > 0);
    fclose(run_check("instances " TMP "/timed/roster.json", TMP "/instances.txt"));
    check_timed_instance_lines(TMP "/instances.txt", "Unity");
    for (size_t d = 0; d < COUNT_OF(timed_roster_damages); ++d) {
        damage_timed_roster(TMP, timed_roster_damages[d].edit, TMP "/broken.json");
        if (run_command("mono " CHECK_EXE " roster " TMP "/broken.json 2>&1", log, sizeof log) == 0)
            fail_msg("a damaged timed state (%s) was read", timed_roster_damages[d].edit);
        check_timed_refusal(log, d);
    }
}

typedef struct roster_contact {
    char state[64];
    unsigned bone;
    double land, lift, fps;
} roster_contact;

/* The contacts of each state's clip, from Python's roster lines at PATH (S: state -> clip, L: clip fps and duration,
 * R: a timed clip's cells, whose contacts sit at cells / duration a second, K: contacts). */
static unsigned state_contacts(const char *path, roster_contact *out, unsigned max)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[8192], states[16][2][256];
    unsigned n = 0, ns = 0;
    while (fgets(line, sizeof line, f))
        if (line[0] == 'S' && ns < 16) assert_int_equal(sscanf(line, "S %*s %255s %255s", states[ns][0], states[ns][1]), 2), ++ns;
    rewind(f);
    double fps = 0, duration = 0, cells;
    char clip[256], foot[256];
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'L') assert_int_equal(sscanf(line, "L %*s %255s %*d %*d %lf %lf", clip, &fps, &duration), 3);
        if (line[0] == 'R' && sscanf(line, "R %*s %*s %lf", &cells) == 1) fps = cells / duration;
        unsigned bone;
        double land, lift;
        if (line[0] != 'K' || sscanf(line, "K %*s %*s %255s %u %lf %lf", foot, &bone, &land, &lift) != 4) continue;
        for (unsigned s = 0; s < ns; ++s)
            if (strcmp(states[s][1], clip) == 0 && n < max) {
                snprintf(out[n].state, sizeof out[n].state, "%s", states[s][0]);
                out[n].bone = bone, out[n].land = land, out[n].lift = lift, out[n].fps = fps;
                ++n;
            }
    }
    fclose(f);
    return n;
}

/* The C reader's matrix for an instance's four numbers: the clip they point at, at the clip time
 * they give. */
static void instance_matrix(const cbpal_file *pal, const float inst[4], double time, unsigned bone, float m[16])
{
    for (uint32_t c = 0; c < pal->header.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(pal, c, &clip);
        int timed = (clip.flags & CBPAL_CLIP_TIMED) != 0; /* its instance counts cells, at -cell_rate x rate */
        if (clip.first_row != (uint32_t)inst[0] || (timed ? clip.cells : clip.frames) != (uint32_t)fabsf(inst[1])) continue;
        double fpos = time * fabs((double)inst[2]) + inst[3] * fabs((double)inst[1]);
        assert_int_equal(cbpal_bone_matrix(pal, c, fpos / (timed ? clip.cell_rate : clip.fps), bone, m), 0);
        return;
    }
    fail_msg("instance numbers %g %g point at no clip", inst[0], inst[1]);
}

/* The herd of the Cow roster in TMP/DIR: its bone matrices (mid-fade and after), SetSpeed's frame and its footsteps,
 * against the C reader at the same instance numbers and the manifest's contacts (Python's lines at ROSTER_LINES).
 * Local rows fade before they compose, which the C reader has no call for: those mid-fade matrices against the C
 * runtime's (cb_runtime_matrices_crossfade, in double where C# and the C reader compute in float: 1e-4). */
static void check_herd(const char *dir, const char *roster_lines)
{
    roster_contact contacts[256];
    unsigned ncontacts = state_contacts(roster_lines, contacts, 256);
    cbpal_file pal;
    cb_palette view;
    cb_error e;
    char err[256], line[8192], line2[8192], path[1024], args[2048];
    snprintf(path, sizeof path, TMP "/%s/cow.pal", dir);
    if (cbpal_open(path, 0, &pal, err, sizeof err)) fail_msg("%s", err);
    if (cb_palette_view(&pal, &view, &e)) fail_msg("%s", e.message);
    double *mats = malloc((size_t)view.bone_count * 16 * sizeof *mats);
    snprintf(args, sizeof args, "herd %s " TMP "/%s/roster.json cow", path, dir);
    FILE *f = run_check(args, TMP "/herd.txt");
    unsigned matrices = 0, faded = 0, steps = 0, speeds = 0;
    double worst = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'I') {
            unsigned i, bone, i2, bone2;
            double t, t2;
            float fade, inst[4], from[4], m[16], want[16], was[16];
            assert_int_equal(sscanf(line, "I %u %u %lf %f %f %f %f %f %f %f %f %f", &i, &bone, &t, &fade, &inst[0], &inst[1], &inst[2],
                                    &inst[3], &from[0], &from[1], &from[2], &from[3]), 12);
            assert_non_null(fgets(line2, sizeof line2, f));
            char *p = line2 + 2;
            i2 = (unsigned)strtoul(p, &p, 10), bone2 = (unsigned)strtoul(p, &p, 10), t2 = strtod(p, &p);
            assert_true(line2[0] == 'N' && i2 == i && bone2 == bone && t2 == t);
            for (int k = 0; k < 16; ++k) m[k] = strtof(p, &p);
            double tol = 1e-5;
            instance_matrix(&pal, inst, t, bone, want);
            if (fade < 1 && view.bone_space == CB_BONE_SPACE_LOCAL) {
                cb_instance to = {inst[0], inst[1], inst[2], inst[3]}, before = {from[0], from[1], from[2], from[3]};
                assert_true(cb_runtime_matrices_crossfade(&view, pal.texels, &before, &to, fade, t, mats));
                for (int k = 0; k < 16; ++k) want[k] = (float)mats[(size_t)bone * 16 + k];
                tol = 1e-4;
            } else if (fade < 1) {
                instance_matrix(&pal, from, t, bone, was);
                for (int k = 0; k < 16; ++k) want[k] = was[k] + (want[k] - was[k]) * fade;
            }
            faded += fade > 0 && fade < 1 && memcmp(inst, from, sizeof inst) != 0;
            for (int k = 0; k < 16; ++k) check_close("herd bone matrix", m[k], want[k], tol, &worst);
            ++matrices;
        } else if (line[0] == 'P') {
            double before, after, frames;
            assert_int_equal(sscanf(line, "P %*u %lf %lf %lf", &before, &after, &frames), 3);
            double d = fmod(fabs(before - after), frames);
            assert_true(fmin(d, frames - d) < 1e-3); /* SetSpeed keeps the frame it is on */
            ++speeds;
        } else if (line[0] == 'F') {
            unsigned bone, found = 0;
            char kind[16], st[256];
            double t;
            float frames, rate, phase;
            assert_int_equal(sscanf(line, "F %*u %u %15s %lf %f %f %f %255s", &bone, kind, &t, &frames, &rate, &phase, st), 7);
            double row = t * fabs((double)rate) + phase * fabs((double)frames), n = fabs((double)frames);
            for (unsigned c = 0; c < ncontacts; ++c) {
                if (contacts[c].bone != bone || strcmp(contacts[c].state, st) != 0) continue;
                double at = (strcmp(kind, "land") == 0 ? contacts[c].land : contacts[c].lift) * contacts[c].fps;
                double d = fmod(fabs(row - at), n);
                found |= fmin(d, n - d) < 1e-3;
            }
            if (!found) fail_msg("footstep at no contact of its clip: %s", line);
            ++steps;
        }
    }
    fclose(f);
    free(mats);
    cb_palette_view_free(&view);
    cbpal_close(&pal);
    printf("  %s herd: %u bone matrices (%u mid-fade), worst relative difference %.3g; %u speed change; %u footsteps on the manifest's "
           "contacts\n", dir, matrices, faded, worst, speeds, steps);
    assert_true(matrices > 100 && faded > 0 && speeds == 1 && steps > 10);
}

static void test_herd_equals_the_c_reader(void **state)
{
    test_roster_equals_the_manifest(state);
    check_herd("roster", TMP "/roster_py.txt");
}

/* The same herd from local, timed rows (every clip timed: its instances count cells, at z < 0; footsteps on cells). */
static void test_timed_herd_equals_the_c_reader(void **state)
{
    (void)state;
    build_check();
    bake_cow_into("timed-cow", "bone_space = \"local\"\ntimed_rows = \"on\"");
    run_or_fail("python3 tests/runtimes/unity/roster_lines.py " TMP "/timed-cow/roster.json > " TMP "/timed_cow_py.txt 2>&1");
    char log[256];
    assert_int_equal(run_command("grep -c '^R ' " TMP "/timed_cow_py.txt", log, sizeof log), 0);
    assert_int_equal(atoi(log), 4); /* the four clips its states play */
    check_herd("timed-cow", TMP "/timed_cow_py.txt");
}

/* The MonoBehaviour, the importers, the asset types and the sample's script against stubs of the
 * Unity API (C# 7.2 for the stubs' `in` parameter, as Unity declares RenderMeshInstanced). */
static void test_unity_facing_code_compiles(void **state)
{
    (void)state;
    char cmd[2048];
    /* As a player build, then as the Editor compiles it (UNITY_EDITOR: CrowdbakeHerd.Reset finds the bone pass kernel). */
    for (int editor = 0; editor < 2; ++editor) {
        snprintf(cmd, sizeof cmd,
                 "mkdir -p %s && mcs -langversion:7.2 -warnaserror -nologo %s -target:library -out:%s/Crowdbake.Unity.dll "
                 "tests/runtimes/unity/stubs/*.cs %s/Runtime/*.cs %s/Runtime/Core/*.cs %s/Editor/*.cs '%s/Samples~/Herd/'*.cs 2>&1",
                 TMP, editor ? "-define:UNITY_EDITOR" : "", TMP, PKG, PKG, PKG, PKG);
        run_or_fail(cmd);
    }
}

/* The shader glue (CrowdbakeUnity.hlsl, CrowdbakeShaderGraph.hlsl) over the shared HLSL runtime:
 * glslang's HLSL front end compiles it to SPIR-V that spirv-val accepts, in all nine encodings. */
static void test_shader_glue_compiles(void **state)
{
    (void)state;
    FILE *runtime = fopen("runtimes/hlsl/crowdbake_palette.hlsl", "r");
    if (!runtime) fail_msg("runtimes/hlsl/crowdbake_palette.hlsl is missing: the Unity shaders include the shared HLSL runtime");
    fclose(runtime);
    const char *layouts[] = {"MAT4", "AFFINE", "QPOS"}, *precisions[] = {"FLOAT", "HALF", "U16"};
    char cmd[2048];
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p) {
            snprintf(cmd, sizeof cmd,
                     "mkdir -p %s && glslangValidator -D -V -S vert -e main -DCB_LAYOUT_%s -DCB_PRECISION_%s %s -o %s/glue.spv "
                     "tests/runtimes/unity/unity_glue.hlsl 2>&1 && spirv-val %s/glue.spv 2>&1",
                     TMP, layouts[l], precisions[p], p == 1 ? "-DCB_POSITIONS_RELATIVE" : "", TMP, TMP);
            run_or_fail(cmd);
        }
    /* Local rows (.pal version 6): qpos, u16 or float, CB_LOCAL_ROWS. */
    for (int p = 0; p < 3; p += 2) {
        snprintf(cmd, sizeof cmd,
                 "glslangValidator -D -V -S vert -e main -DCB_LAYOUT_QPOS -DCB_PRECISION_%s -DCB_LOCAL_ROWS -o %s/glue.spv "
                 "tests/runtimes/unity/unity_glue.hlsl 2>&1 && spirv-val %s/glue.spv 2>&1",
                 precisions[p], TMP, TMP);
        run_or_fail(cmd);
    }
    printf("  Unity shader glue: 9 encodings and local rows (qpos u16, float) compile (glslang, HLSL) and validate (spirv-val)\n");
}

/* How many lines of `text` contain `needle`. */
static unsigned count_lines_with(const char *text, const char *needle)
{
    unsigned n = 0;
    for (const char *p = text; (p = strstr(p, needle)) != NULL; p += strlen(needle)) ++n;
    return n;
}

/* glslangValidator -D -V -S STAGE -e ENTRY DEFINES FILE, then spirv-val; returns how many OpImageWrite the SPIR-V
 * has (spirv-dis): the bone pass kernel's three stores must survive. */
static unsigned compile_and_validate(const char *stage, const char *entry, const char *defines, const char *file)
{
    char cmd[2048], log[256];
    snprintf(cmd, sizeof cmd, "glslangValidator -D -V -S %s -e %s %s -o %s/bone.spv %s 2>&1 && spirv-val %s/bone.spv 2>&1", stage, entry,
             defines, TMP, file, TMP);
    run_or_fail(cmd);
    snprintf(cmd, sizeof cmd, "spirv-dis %s/bone.spv | grep -c OpImageWrite || true", TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s:\n%s", cmd, log);
    return (unsigned)strtoul(log, NULL, 10);
}

/* The bone pass's shaders: the compute kernel (CrowdbakeBonePass.compute, including the shared runtime as the
 * package does) in every encoding and for local rows, its three texture stores kept; the draw's CB_BONE_TEXTURE
 * variant of the glue (the .shader files' CrowdbakeSkin and Shader Graph's) likewise; and the keywords: the kernel
 * compiles the palette's encodings as the shaders do, and both shaders (every pass: the keyword is in the built-in
 * shader's CGPROGRAM, which addshadow reuses, and in URP's HLSLINCLUDE) have the CB_BONE_TEXTURE variant. */
static void test_bone_pass_shaders_compile(void **state)
{
    (void)state;
    run_or_fail("mkdir -p " TMP);
    const char *layouts[] = {"MAT4", "AFFINE", "QPOS"}, *precisions[] = {"FLOAT", "HALF", "U16"};
    const char *kernel = PKG "/Runtime/Shaders/CrowdbakeBonePass.compute", *glue = "tests/runtimes/unity/unity_glue.hlsl";
    char defines[256];
    unsigned kernels = 0, variants = 0;
    for (int l = 0; l < 3; ++l)
        for (int p = 0; p < 3; ++p) {
            snprintf(defines, sizeof defines, "-DCB_LAYOUT_%s -DCB_PRECISION_%s %s", layouts[l], precisions[p],
                     p == 1 ? "-DCB_POSITIONS_RELATIVE" : "");
            assert_int_equal(compile_and_validate("comp", "CrowdbakeBonePass", defines, kernel), 3);
            ++kernels;
            strcat(defines, " -DCB_BONE_TEXTURE");
            compile_and_validate("vert", "main", defines, glue);
            ++variants;
        }
    for (int p = 0; p < 3; p += 2) { /* local rows: the kernel composes each bone's chain */
        snprintf(defines, sizeof defines, "-DCB_LAYOUT_QPOS -DCB_PRECISION_%s -DCB_LOCAL_ROWS", precisions[p]);
        assert_int_equal(compile_and_validate("comp", "CrowdbakeBonePass", defines, kernel), 3);
        ++kernels;
        strcat(defines, " -DCB_BONE_TEXTURE");
        compile_and_validate("vert", "main", defines, glue);
        ++variants;
    }
    char *compute = read_whole_file(kernel, NULL), *builtin = read_whole_file(PKG "/Runtime/Shaders/CrowdbakeHerd.shader", NULL),
         *urp = read_whole_file(PKG "/Runtime/Shaders/CrowdbakeHerdURP.shader", NULL);
    assert_non_null(compute), assert_non_null(builtin), assert_non_null(urp);
    const char *encodings[] = {"#pragma multi_compile_local CB_LAYOUT_MAT4 CB_LAYOUT_AFFINE CB_LAYOUT_QPOS\n",
                               "#pragma multi_compile_local CB_PRECISION_FLOAT CB_PRECISION_HALF CB_PRECISION_U16\n",
                               "#pragma multi_compile_local _ CB_POSITIONS_RELATIVE\n", "#pragma multi_compile_local _ CB_LOCAL_ROWS\n"};
    for (size_t k = 0; k < COUNT_OF(encodings); ++k)
        if (count_lines_with(compute, encodings[k]) != 1 || count_lines_with(builtin, encodings[k]) != 1 ||
            count_lines_with(urp, encodings[k]) != 1)
            fail_msg("the kernel and both shaders must each have once: %s", encodings[k]);
    const char *bone_texture = "#pragma multi_compile_local _ CB_BONE_TEXTURE";
    assert_int_equal(count_lines_with(builtin, bone_texture), 1);
    assert_int_equal(count_lines_with(urp, bone_texture), 1);
    char *hlslinclude = strstr(urp, "HLSLINCLUDE"), *first_pass = strstr(urp, "Pass\n");
    assert_true(hlslinclude && first_pass && strstr(hlslinclude, bone_texture) < first_pass); /* every URP pass */
    free(compute), free(builtin), free(urp);
    printf("  bone pass: the kernel in %u encodings (local rows too) and the glue's CB_BONE_TEXTURE variant in %u compile "
           "(glslang, HLSL) and validate (spirv-val), 3 texture stores each kernel; keywords alike in the kernel and both shaders\n",
           kernels, variants);
}

/* A number after `name = ` in `text` (an `export const` of the web runtime). */
static long web_constant(const char *text, const char *name)
{
    char key[128];
    snprintf(key, sizeof key, "export const %s = ", name);
    const char *p = strstr(text, key);
    if (!p) fail_msg("runtimes/web/crowdbake_bones.mjs has no '%s'", key);
    return strtol(p + strlen(key), NULL, 10);
}

/* Core/BonePass.cs against the WebGL2 runtime: its thresholds are crowdbake_bones.mjs's AUTO_BONE_PASS_VERTICES(_LOCAL),
 * and every choice for herds around them, global and local, each mode and a given threshold, is Crowd.choice's rule
 * (skinned vertices a frame >= the threshold) with its reason; the layout is the web BonePass's (rows = min(herd,
 * texture size), blocks side by side, refused past the texture's width) and the kernel's dispatch covers every
 * (instance, bone) once, at the texel cb_passed_bone reads. */
static void test_bone_pass_rule_matches_the_web(void **state)
{
    (void)state;
    build_check();
    char *bones = read_whole_file("runtimes/web/crowdbake_bones.mjs", NULL), *crowd = read_whole_file("runtimes/web/crowdbake_crowd.mjs", NULL);
    assert_non_null(bones), assert_non_null(crowd);
    long web_global = web_constant(bones, "AUTO_BONE_PASS_VERTICES"), web_local = web_constant(bones, "AUTO_BONE_PASS_VERTICES_LOCAL");
    if (!strstr(crowd, "vertices >= this.bonePassVertices")) fail_msg("crowdbake_crowd.mjs's choice() no longer takes the pass at >= its threshold");
    free(bones), free(crowd);
    FILE *f = run_check("bonepass", TMP "/bonepass.txt");
    char line[1024];
    unsigned decisions = 0, taken = 0, layouts = 0, refused = 0, unavailable = 0;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = 0;
        if (line[0] == 'T') {
            long g, l;
            assert_int_equal(sscanf(line, "T %ld %ld", &g, &l), 2);
            if (g != web_global || l != web_local) fail_msg("C# thresholds %ld/%ld, the web's %ld/%ld", g, l, web_global, web_local);
        } else if (line[0] == 'D') {
            int mode, local, given, n, v, pass, threshold, at;
            assert_int_equal(sscanf(line, "D %d %d %d %d %d %d %d %n", &mode, &local, &given, &n, &v, &pass, &threshold, &at), 7);
            const char *reason = line + at;
            long want_threshold = mode == 1 ? 0 : mode == 2 ? 2147483647L : given > 0 ? given : local ? web_local : web_global;
            int want = mode == 1 || (mode == 0 && (long)n * v >= want_threshold);
            if (pass != want || threshold != want_threshold) fail_msg("%s: want pass %d threshold %ld", line, want, want_threshold);
            if (mode == 0 && !strstr(reason, pass ? " skinned vertices a frame >= " : " skinned vertices a frame < "))
                fail_msg("%s: the reason does not give the count against the threshold", line);
            if (mode == 0 && (strstr(reason, "local rows") != NULL) != (local && given == 0))
                fail_msg("%s: the reason must name local rows exactly when their threshold is the rule's", line);
            ++decisions, taken += pass;
        } else if (line[0] == 'U') {
            int pass;
            assert_int_equal(sscanf(line, "U %*d %d", &pass), 1);
            if (pass || !strstr(line, "no bone pass here: no compute shaders")) fail_msg("%s: should skin per vertex, saying why", line);
            ++unavailable;
        } else if (line[0] == 'L') {
            long n, b, max, rows, blocks, width, gx, gy, bytes, per, threads, once, misplaced;
            assert_int_equal(sscanf(line, "L %ld %ld %ld %ld %ld %ld %ld %ld %ld %ld %ld %ld %ld", &n, &b, &max, &rows, &blocks, &width, &gx,
                                    &gy, &bytes, &per, &threads, &once, &misplaced), 13);
            long want_rows = n < max ? n : max, want_blocks = (n + want_rows - 1) / want_rows;
            if (rows != want_rows || blocks != want_blocks || width != want_blocks * b || width > max || gx != (width + 7) / 8 ||
                gy != (rows + 7) / 8 || bytes != width * rows * 48 || per != b * 48 + 48)
                fail_msg("%s: the web's layout has %ld rows, %ld blocks", line, want_rows, want_blocks);
            if (threads != n * b || once != n * b || misplaced) fail_msg("%s: the dispatch must write each (instance, bone) once, in place", line);
            ++layouts;
        } else if (line[0] == 'E') {
            long n, b, max;
            assert_int_equal(sscanf(line, "E %ld %ld %ld", &n, &b, &max), 3);
            long rows = n < max ? n : max;
            if ((n + rows - 1) / rows * b <= max) fail_msg("%s: refused, yet it fits", line);
            ++refused;
        } else {
            fail_msg("unexpected line from CrowdbakeCheck bonepass: %s", line);
        }
    }
    fclose(f);
    printf("  bone pass rule: thresholds %ld (global) and %ld (local rows) as the web's; %u choices (%u take the pass) as the web's "
           "rule; %u layouts whose dispatch writes every (instance, bone) once in place, %u refused as too wide; %u unavailable\n",
           web_global, web_local, decisions, taken, layouts, refused, unavailable);
    assert_true(decisions == 3 * 2 * 2 * 10 * 4 && taken > 0 && taken < decisions && layouts >= 8 && refused >= 2 && unavailable == 2);
}

/* The runtime conformance cases of local rows (.pal version 6: conformance.h's local_*) and timed rows (.pal
 * version 7: timed_*, broken-timed-map-ignored): the C# reader's bone matrices (PalFile.InstanceBoneMatrix,
 * cross-faded as the herd does; local rows composed, timed clips through their maps) skin every instance of
 * every group within the cases' tolerance of the C runtime's expected positions, cross-fades included
 * (conf_expected fades local rows before composing, cb_runtime_matrices_crossfade); the map ignored misses by far. */
static void test_local_and_timed_conformance_cases(void **state)
{
    (void)state;
    build_check();
    conformance conf;
    conformance_make(&conf, TMP "/conformance");
    int ran = 0, timed = 0, caught = 0;
    for (int i = 0; i < conf.case_count; ++i) {
        const conf_case *k = &conf.cases[i];
        if (!k->local && !k->timed) continue;
        char args[1024], out[512];
        snprintf(out, sizeof out, TMP "/conformance/%s.cs.out", k->name);
        snprintf(args, sizeof args, "conformance " TMP "/conformance %s %s", k->name, out);
        fclose(run_check(args, TMP "/conformance.txt"));
        double units, ratio = conformance_compare_file(&conf, k, out, &units);
        printf("  %-24s %7zu positions, cross-fades included: C# vs C runtime %.2g (%.3f of the tolerance)\n", k->name,
               conf_positions(&conf, k), units, ratio);
        if (k->broken) assert_true(ratio > 10), ++caught;
        else assert_true(ratio <= 1);
        ++ran;
        timed += k->timed && !k->broken;
    }
    conformance_free(&conf);
    assert_true(ran >= 11 && timed >= 7 && caught == 1);
}

/* Timed rows (.pal version 7) made by hand from the quadruped's untimed bakes, until the bake writes them:
 * CrowdbakeCheck's MakeTimed gives each clip a grid twice as fine as its rows (row k on cell 2k) and its map
 * over the rows before it; the reader takes the table and the map, and the timed clip's bone matrices
 * (PalFile.BoneMatrix, the herd's BoneMatrixAt, travel offsets) equal the untimed clip's; the same numbers
 * read without the map are far off; a map naming a row past its clip is refused. */
static void test_timed_rows_by_hand(void **state)
{
    (void)state;
    build_check();
    const char *options[] = {"--layout qpos --precision float", "--layout qpos --precision half", "--layout qpos --precision u16",
                             "--layout mat4 --precision half", "--layout affine --precision u16"};
    char quadruped[1024], cmd[4096], line[1024];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    unsigned clips = 0;
    for (int o = 0; o < 5; ++o) {
        snprintf(cmd, sizeof cmd, "%s bake %s -o %s/timed.pal --root-motion in-place -q %s 2>&1", crowdbake_exe(), quadruped, TMP,
                 options[o]);
        run_or_fail(cmd);
        FILE *f = run_check("timed " TMP "/timed.pal", TMP "/timed.txt");
        double worst = 0, without = INFINITY;
        unsigned here = 0, refused = 0;
        while (fgets(line, sizeof line, f)) {
            unsigned clip, cells;
            double d, travel, w;
            if (sscanf(line, "T %u %u %lf %lf %lf", &clip, &cells, &d, &travel, &w) == 5) {
                worst = fmax(worst, fmax(d, travel)), without = fmin(without, w), ++here;
                continue;
            }
            if (strncmp(line, "V badmap: clip 1 (", 18) != 0 || !strstr(line, "map's cell")) fail_msg("bad map: %s", line);
            ++refused;
        }
        fclose(f);
        printf("  quadruped %s, %u clips made timed: bone matrices vs untimed %.3g, without the map %.3g; bad map refused\n",
               options[o], here, worst, without);
        assert_true(here >= 3 && refused == 1 && worst <= 1e-5 && without > 0.1);
        clips += here;
    }
    assert_true(clips >= 15);
}

/* Local rows whose every parent comes after its children (the spec: do not assume parent < child):
 * the C# composed matrices equal the C reader's, and bone n - 1 - j's equal bone j's of the same
 * bake in the model's order. */
static void test_parents_after_children(void **state)
{
    (void)state;
    build_check();
    write_local_quadruped(TMP "/ordered.pal", false);
    write_local_quadruped(TMP "/reversed.pal", true);
    unsigned matrices = 0;
    double worst = compare_pal(TMP "/reversed.pal", &matrices);
    cbpal_file a, b;
    char err[256];
    if (cbpal_open(TMP "/ordered.pal", 0, &a, err, sizeof err) || cbpal_open(TMP "/reversed.pal", 0, &b, err, sizeof err))
        fail_msg("%s", err);
    uint32_t n = a.header.bone_count, after = 0;
    double moved = 0;
    for (uint32_t j = 0; j < n; ++j) {
        cbpal_bone bone;
        cbpal_get_bone(&b, j, &bone);
        after += bone.parent > (int32_t)j;
        for (uint32_t c = 0; c < a.header.clip_count; ++c) {
            float m[16], r[16];
            assert_int_equal(cbpal_bone_matrix(&a, c, 0.37 * (c + 1), j, m), 0);
            assert_int_equal(cbpal_bone_matrix(&b, c, 0.37 * (c + 1), n - 1 - j, r), 0);
            for (int k = 0; k < 16; ++k) moved = fmax(moved, fabs((double)m[k] - r[k]));
        }
    }
    cbpal_close(&a), cbpal_close(&b);
    printf("  quadruped local u16, bones reversed (%u of %u parents after their child): %u C# matrices, worst relative "
           "difference C# vs C %.3g; bone n-1-j vs bone j of the ordered bake %.3g\n", after, n, matrices, worst, moved);
    assert_true(after > 0 && moved < 1e-5);
}

/* ---- the bone pass kernel itself (CrowdbakeBonePass.compute, as the package has it) on Mesa's lavapipe ---- */

#define UNITY_BONE_ROWS 7 /* the herd's rows if SystemInfo.maxTextureSize were 7: several blocks, the last one part full */

/* The kernel's source as the package has it, its resources given the bindings Unity gives them by name
 * (SetBuffer, SetTexture, SetFloat, SetInt): each declaration must be found once. */
static char *unity_kernel_source(const char *prefix, const char *const broken[2])
{
    char *kernel = read_whole_file(PKG "/Runtime/Shaders/CrowdbakeBonePass.compute", NULL);
    assert_non_null(kernel);
    if (broken) { /* a planted mistake: broken[0]'s line replaced by broken[1] */
        char *b = break_shader(kernel, broken[0], broken[1]);
        free(kernel);
        kernel = b;
    }
    const char *from[] = {"StructuredBuffer<float4> _CbInstances;", "RWTexture2D<float4> _CbBonesOut0;", "RWTexture2D<float4> _CbBonesOut1;",
                          "RWTexture2D<float4> _CbBonesOut2;", "float _CbTime;\nint _CbCount;\nint _CbBoneRows;"};
    const char *to[] = {"[[vk::binding(3)]] StructuredBuffer<float4> _CbInstances;",
                        "[[vk::binding(4)]] [[vk::image_format(\"rgba32f\")]] RWTexture2D<float4> _CbBonesOut0;",
                        "[[vk::binding(5)]] [[vk::image_format(\"rgba32f\")]] RWTexture2D<float4> _CbBonesOut1;",
                        "[[vk::binding(6)]] [[vk::image_format(\"rgba32f\")]] RWTexture2D<float4> _CbBonesOut2;",
                        "[[vk::binding(7)]] cbuffer unity_kernel { float _CbTime; int _CbCount; int _CbBoneRows; };"};
    size_t size = strlen(prefix) + strlen(kernel) + 4096;
    char *src = malloc(size);
    snprintf(src, size, "%s", prefix);
    const char *rest = kernel;
    for (size_t k = 0; k < COUNT_OF(from); ++k) {
        const char *at = strstr(rest, from[k]);
        if (!at || strstr(at + 1, from[k])) fail_msg("CrowdbakeBonePass.compute: '%s' must be declared once, in this order", from[k]);
        strncat(src, rest, (size_t)(at - rest));
        strcat(src, to[k]);
        rest = at + strlen(from[k]);
    }
    strcat(src, rest);
    free(kernel);
    return src;
}

/* glslang (entry CrowdbakeBonePass, named main as the harness runs it; the package's include path: CrowdbakePalette.hlsl reaches the shared runtime) and spirv-val. */
static uint32_t *compile_unity_kernel(const char *src, size_t *bytes)
{
    char cmd[2048], log[8192];
    write_text(TMP "/unity_bone_pass.hlsl", src);
    snprintf(cmd, sizeof cmd, "glslangValidator -V -D -S comp -e main --source-entrypoint CrowdbakeBonePass --target-env vulkan1.1 -I%s/Runtime/Shaders -o %s "
             "%s 2>&1 && spirv-val --target-env vulkan1.1 %s 2>&1", PKG, TMP "/unity_bone_pass.spv", TMP "/unity_bone_pass.hlsl",
             TMP "/unity_bone_pass.spv");
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s:\n%s", cmd, log);
    uint32_t *spv = (uint32_t *)read_whole_file(TMP "/unity_bone_pass.spv", bytes);
    assert_non_null(spv);
    return spv;
}

/* The per-instance data CrowdbakeHerd uploads (inst, from, fade = (start, length, 0, 0)) for the harness's samples, at one
 * herd clock `now` as a herd has: each phase moved so that `now` plays the sample's moment, the fade started so that
 * its weight at `now` is the sample's. */
static float *unity_instances(const sample *s, uint32_t n, double now)
{
    float *d = calloc((size_t)n * 12, sizeof *d);
    for (uint32_t i = 0; i < n; ++i) {
        const cb_instance *c[2] = {&s[i].inst, &s[i].from};
        for (int k = 0; k < 2; ++k) {
            double frames = fabs(c[k]->frame_count);
            float v[4] = {(float)c[k]->first_row, (float)c[k]->frame_count, (float)c[k]->rate,
                          (float)(c[k]->phase + (s[i].time - now) * c[k]->rate / frames)};
            memcpy(d + i * 12 + k * 4, v, sizeof v);
        }
        d[i * 12 + 8] = (float)(now - s[i].fade); /* weight saturate((now - start) / 1) = the sample's */
        d[i * 12 + 9] = 1;
    }
    return d;
}

/* Runs the package's kernel over the samples (dispatched as CrowdbakeHerd dispatches it: BonePassLayout's groups of
 * 8 x 8 over the textures), then skins from its textures; returns the harness's 12 floats per (sample, vertex). */
static float *gpu_unity_bone_pass(const cb_palette *p, const cb_primitive *prim, const sample *s, uint32_t n, const char *library,
                                  const char *const broken[2])
{
    bool u16 = p->precision == CB_PRECISION_U16; /* Unity's RGBA64: UNORM16, the kernel's own CB_U16_UNORM */
    static char prefix[4096], skin_src[1 << 17];
    hlsl_globals_prefix(prefix, sizeof prefix, p, u16, "");
    char *own = strstr(prefix, "#define CB_U16_UNORM\n");
    if (own) memmove(own, own + strlen("#define CB_U16_UNORM\n"), strlen(own + strlen("#define CB_U16_UNORM\n")) + 1);
    char *kernel_src = unity_kernel_source(prefix, broken);
    size_t bytes[2];
    uint32_t *spv[2] = {compile_unity_kernel(kernel_src, &bytes[0]), NULL};
    char extra[512];
    snprintf(extra, sizeof extra, "static const float cb_bone_rows = %d;\n#define CB_BONE_TEXTURE\n[[vk::binding(3)]] Texture2D<float4> cb_bones0;\n"
             "[[vk::binding(4)]] Texture2D<float4> cb_bones1;\n[[vk::binding(5)]] Texture2D<float4> cb_bones2;\n", UNITY_BONE_ROWS);
    hlsl_globals_prefix(skin_src, sizeof skin_src, p, u16, extra);
    size_t used = strlen(skin_src);
    snprintf(skin_src + used, sizeof skin_src - used, "%s\n%s", library, HARNESS_BONE_SKIN_MAIN);
    spv[1] = compile_hlsl(skin_src, "unity_bone_skin", "", &bytes[1]);
    uint32_t rows = UNITY_BONE_ROWS, blocks = (n + rows - 1) / rows, width = blocks * p->bone_count, verts = prim->vertex_count;
    struct { float time; int32_t count, rows, pad; } clock = {0.5f, (int32_t)n, (int32_t)rows, 0};
    float *instances = unity_instances(s, n, clock.time);
    header_block h = header_of(p, verts, n);
    vkc_resource r[8] = {upload_palette(&vk, p, u16, false), upload_bind_positions(&vk, p),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &h, sizeof h),
                         vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, instances, (size_t)n * 48)};
    for (int k = 0; k < 3; ++k) r[4 + k] = vkc_image(&vk, VK_FORMAT_R32G32B32A32_SFLOAT, width, rows, 16, NULL, true);
    r[7] = vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &clock, sizeof clock);
    vkc_pipeline pass = vkc_compute(&vk, spv[0], bytes[0], r, 8);
    vkc_resource skin[8] = {r[0], r[1], r[2], r[4], r[5], r[6], upload_vertices(&vk, prim),
                            vkc_buffer(&vk, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, NULL, (size_t)n * verts * 48)};
    for (int k = 3; k < 6; ++k) skin[k].type = VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE; /* written by the kernel, read here */
    vkc_pipeline skinning = vkc_compute(&vk, spv[1], bytes[1], skin, 8);
    VkCommandBuffer cmd = vkc_begin(&vk);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pass.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pass.layout, 0, 1, &pass.set, 0, NULL);
    vkCmdDispatch(cmd, (width + 7) / 8, (rows + 7) / 8, 1); /* BonePassLayout.ThreadGroupsX, ThreadGroupsY */
    vkc_barrier(cmd);
    vkc_dispatch(cmd, &skinning, (uint32_t)(((size_t)n * verts + 63) / 64));
    vkc_submit(&vk, cmd);
    float *out = malloc((size_t)n * verts * 48);
    vkc_read(&vk, &skin[7], out);
    vkc_free_pipeline(&vk, &pass), vkc_free_pipeline(&vk, &skinning);
    for (int i = 0; i < 8; ++i) vkc_free(&vk, &r[i]);
    vkc_free(&vk, &skin[6]), vkc_free(&vk, &skin[7]);
    free(spv[0]), free(spv[1]), free(kernel_src), free(instances);
    return out;
}

/* Worst position error / tolerance of the package's kernel (broken as `broken` says, or not) on the quadruped sample;
 * the normals' / 1e-5 in *normal_ratio. */
static double unity_kernel_case(cb_layout l, cb_precision pr, bool local, const char *library, const char *const broken[2],
                                double *normal_ratio)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/quadruped.glb", samples_dir());
    fixture f;
    bake_space(path, l, pr, false, local ? CB_BONE_SPACE_LOCAL : CB_BONE_SPACE_GLOBAL, &f);
    sample samples[64];
    uint32_t n = make_samples(&f.palette, samples, 64), faded = 0;
    for (uint32_t i = 0; i < n; ++i) samples[i].dt = 0, faded += samples[i].fade < 1;
    assert_true(faded > 0);
    const cb_primitive *prim = &f.model->primitives[0];
    float *gpu = gpu_unity_bone_pass(&f.palette, prim, samples, n, library, broken);
    double pe, ne, tol = tolerance(&f);
    compare(&f.palette, prim, samples, n, gpu, &pe, &ne);
    if (!broken)
        printf("  Unity kernel %-6s %-5s%s: %u instances (%u mid-fade, %d a block) x %u vertices: positions %.2g (%.3f of the "
               "tolerance), normals %.2g\n", cb_layout_name(l), cb_precision_name(pr), local ? " local" : "", n, faded, UNITY_BONE_ROWS,
               prim->vertex_count, pe, pe / tol, ne);
    *normal_ratio = ne / 1e-5;
    free(gpu);
    release(&f);
    return pe / tol;
}

/* The package's kernel on lavapipe, fed as CrowdbakeHerd feeds it (one herd clock, its instance buffer, blocks of rows,
 * BonePassLayout's dispatch): the quadruped sample's instances skinned from its textures equal the C runtime
 * (cb_runtime_matrices_crossfade, which `crowdbake verify` compares with exact skinning) within test_gl's tolerance,
 * cross-fades included, global and local rows; a kernel whose fade runs backwards, or whose threads take the wrong
 * instance, misses by far. */
static void test_bone_pass_kernel_matches_the_c_runtime(void **state)
{
    (void)state;
    if (!have_device) skip();
    run_or_fail("mkdir -p " TMP);
    char *lib = read_whole_file("runtimes/hlsl/crowdbake_palette.hlsl", NULL);
    assert_non_null(lib);
    struct { cb_layout l; cb_precision p; bool local; } cases[] = {{CB_LAYOUT_QPOS, CB_PRECISION_U16, false}, {CB_LAYOUT_MAT4, CB_PRECISION_FLOAT, false},
        {CB_LAYOUT_AFFINE, CB_PRECISION_HALF, false}, {CB_LAYOUT_QPOS, CB_PRECISION_U16, true}, {CB_LAYOUT_QPOS, CB_PRECISION_FLOAT, true}};
    double normals;
    for (size_t c = 0; c < COUNT_OF(cases); ++c) {
        double positions = unity_kernel_case(cases[c].l, cases[c].p, cases[c].local, lib, NULL, &normals);
        assert_true(positions <= 1 && normals <= 1);
    }
    static const char *const backwards[2] = {"cb:unity-fade",
        "    float weight = fade.y > 0.0 ? saturate((fade.x - _CbTime) / fade.y) : 1.0;"};
    static const char *const wrong_instance[2] = {"cb:unity-instance", "    int instance = block * (_CbBoneRows + 1) + int(id.y);"};
    double a = unity_kernel_case(CB_LAYOUT_QPOS, CB_PRECISION_U16, false, lib, backwards, &normals);
    double b = unity_kernel_case(CB_LAYOUT_QPOS, CB_PRECISION_U16, true, lib, wrong_instance, &normals);
    printf("  Unity kernel broken: fade backwards %.0f tolerances, the wrong instance a block %.0f\n", a, b);
    assert_true(a > 10 && b > 10);
    free(lib);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reader_equals_the_c_reader),
        cmocka_unit_test(test_reader_verdicts_match),
        cmocka_unit_test(test_roster_equals_the_manifest),
        cmocka_unit_test(test_roster_timed_states),
        cmocka_unit_test(test_herd_equals_the_c_reader),
        cmocka_unit_test(test_timed_herd_equals_the_c_reader),
        cmocka_unit_test(test_unity_facing_code_compiles),
        cmocka_unit_test(test_shader_glue_compiles),
        cmocka_unit_test(test_bone_pass_shaders_compile),
        cmocka_unit_test(test_bone_pass_rule_matches_the_web),
        cmocka_unit_test(test_bone_pass_kernel_matches_the_c_runtime),
        cmocka_unit_test(test_local_and_timed_conformance_cases),
        cmocka_unit_test(test_timed_rows_by_hand),
        cmocka_unit_test(test_parents_after_children),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
