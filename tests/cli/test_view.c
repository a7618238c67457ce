/* test_view.c - `crowdbake view` as a user runs it, in headless Chromium (tests/runtimes/browser/view_check.mjs):
 * on the Cow (../shared, a real third-party animal) it bakes, serves on an ephemeral port, prints the
 * URL, and the page shows 1,000 cows in a mix of idle, walk and gallop: not blank, in frame, moving
 * between two times, in one draw call per herd, with no console error; the palette half and the
 * VAT half (exact skinning, from `crowdbake vat`) cover the same pixels; Ctrl-C stops it with exit
 * 0; ?count=N shows N instances for any N (capped at the viewer's 100,000). The same run with a
 * deliberately broken shader (texels of a bone swapped) must fail the palette-vs-VAT comparison,
 * so the comparison is shown to catch a wrong palette. Fox with timed rows is drawn beside its VAT too. */
#define _DEFAULT_SOURCE
#include "testutil.h"
#include "view_server.h"

#include <limits.h>
#include <math.h>
#include <unistd.h>

#define TMP TEST_TMP "/view"

static char out[1 << 16];

/* The number after "KEY": in view_check's JSON line (its first occurrence). */
static double number(const char *key)
{
    char pattern[128];
    snprintf(pattern, sizeof pattern, "\"%s\":", key);
    const char *at = strstr(out, pattern);
    if (!at) fail_msg("no %s in the viewer check's output:\n%s", key, out);
    at += strlen(pattern);
    if (*at == '[') ++at;
    return atof(at);
}

/* more: the page opened again with each of these as ?count= (view_check's MORE,COUNTS), or "". */
static int run_view(const char *env, const char *cache, const char *shot, const char *more)
{
    char model[PATH_MAX], cmd[4 * PATH_MAX];
    shared_path(model, sizeof model, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s node tests/runtimes/browser/view_check.mjs %s %s %s %s 1000 960x540 '%s' 2>&1", env, crowdbake_exe(), model,
             cache, shot, more);
    int rc = run_command(cmd, out, sizeof out);
    printf("%s", out);
    return rc;
}

static void test_view_shows_a_moving_herd_of_cows(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    FILE *installed = fopen("runtimes/web/node_modules/.package-lock.json", "r");
    if (!installed) fail_msg("web: npm packages not installed (make installs them; or: cd web && npm ci)");
    fclose(installed);
    assert_int_equal(run_view("", TMP "/cache", TMP "/viewer.png", "333,0,250000,lots"), 0);
    assert_non_null(strstr(out, "\"exit\":{\"code\":0,"));
    assert_non_null(strstr(out, "crowdbake: viewer stopped"));
    assert_non_null(strstr(out, "\"printed\":[\"cow              baked"));
    assert_non_null(strstr(out, "http://127.0.0.1:"));
    assert_non_null(strstr(out, "\"console_errors\":[]"));
    assert_non_null(strstr(out, "\"error\":\"\""));
    assert_non_null(strstr(out, "\"idle\"") && strstr(out, "\"walk\"") && strstr(out, "\"gallop\""));
    double left = number("coverage_at_1"), changed = number("changed_pixels"), pixels = number("pixels"),
           mismatch = number("palette_vs_vat_mismatch");
    printf("  herd covers %.1f%% of the palette half; %.1f%% of the pixels change between t = 1.0 and 1.4 s; palette and VAT "
           "silhouettes differ on %.2f%% of the covered pixels\n", 100 * left, 100 * changed / pixels, 100 * mismatch);
    assert_true(left > 0.02 && left < 0.6);          /* not blank, the herd in frame (not one cow filling it) */
    assert_true(changed > 0.01 * pixels);             /* they move */
    assert_true(mismatch < 0.02);                     /* the palette draws what exact skinning draws */
    assert_int_equal((int)number("drawCalls"), 2);   /* one per herd: palette, VAT */
    assert_int_equal((int)number("instances"), 1000);
    /* VRAM on screen: the palette (local rows, the default bake's) and the 118x larger VAT. */
    assert_true(number("vatBytes") > 50 * number("paletteBytes"));
    assert_non_null(strstr(out, "palette qpos/u16 local "));
    /* ?count=N for any N, not only the menu's 100, 1000, 10000 and 100000 (333 used to show an
     * empty field; 250000 threw past the crowd's capacity): the menu gains N, past 100,000 is
     * capped there, and what is not a number keeps 1000; the panel says which. */
    static const char *const counts[] = {
        "{\"query\":\"333\",\"instances\":333,\"selected\":\"333\",\"drawCalls\":2,\"notice\":\"\",\"error\":\"\",\"console_errors\":[]}",
        "{\"query\":\"0\",\"instances\":0,\"selected\":\"0\",\"drawCalls\":0,\"notice\":\"\",\"error\":\"\",\"console_errors\":[]}",
        "{\"query\":\"250000\",\"instances\":100000,\"selected\":\"100000\",\"drawCalls\":null,"
        "\"notice\":\"?count=250000: capped at 100000 instances, the viewer's capacity\",\"error\":\"\",\"console_errors\":[]}",
        "{\"query\":\"lots\",\"instances\":1000,\"selected\":\"1000\",\"drawCalls\":2,"
        "\"notice\":\"?count=lots: not a whole number of instances; showing 1000\",\"error\":\"\",\"console_errors\":[]}",
    };
    for (size_t i = 0; i < COUNT_OF(counts); ++i)
        if (!strstr(out, counts[i])) fail_msg("expected %s in the viewer check's output", counts[i]);
}

/* A palette with timed rows (Fox baked with local rows: its Run on its keys, a map of 139 cells at 120 Hz) beside the
 * VAT of the same clips (`vat --like`: the Run at its cells' rate, one frame a cell): the VAT's frames are no longer
 * the palette's rows, and each instance's numbers are the VAT's own (crowdbake_vat.mjs vatLayout). */
static void test_view_shows_a_vat_beside_timed_rows(void **state)
{
    (void)state;
    char fox[PATH_MAX], toml[2 * PATH_MAX], cmd[4 * PATH_MAX];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    char *abs_fox = realpath(fox, NULL);
    assert_non_null(abs_fox);
    assert_int_equal(system("mkdir -p " TMP "/fox"), 0);
    snprintf(toml, sizeof toml,
             "[bake]\nout_dir = \"out\"\nbone_space = \"local\"\n[animal.fox]\nmodel = \"%s\"\n"
             "states = { idle = [\"survey\"], walk = [\"walk\"], run = [\"run\"] }\ndefault_state = \"run\"\n", abs_fox);
    free(abs_fox);
    write_text(TMP "/fox/fox.toml", toml);
    snprintf(cmd, sizeof cmd, "node tests/runtimes/browser/view_check.mjs %s " TMP "/fox/fox.toml " TMP "/fox/cache " TMP
             "/fox/viewer.png 200 960x540 2>&1", crowdbake_exe());
    int rc = run_command(cmd, out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    char log[4096];
    assert_int_equal(run_command("grep -c '\"timed_rows\"' " TMP "/fox/out/roster.json", log, sizeof log), 0);
    assert_int_equal(atoi(log), 1); /* the Run */
    assert_non_null(strstr(out, "\"console_errors\":[]"));
    assert_non_null(strstr(out, "\"error\":\"\""));
    double mismatch = number("palette_vs_vat_mismatch");
    printf("  Fox, timed Run: palette and VAT silhouettes differ on %.2f%% of the covered pixels\n", 100 * mismatch);
    assert_int_equal((int)number("drawCalls"), 2); /* the VAT is drawn beside it */
    assert_true(number("vatBytes") > 50 * number("paletteBytes"));
    assert_true(mismatch < 0.02);
    assert_non_null(strstr(out, "palette qpos/u16 local ")); /* the panel names the local rows */
}

static void test_a_broken_palette_shader_is_caught(void **state)
{
    (void)state;
    /* A folder laid out as the installed one (viewer/, web/, glsl/) whose shader reads a bone's
     * texels in the wrong order (quaternion and position swapped, for the default qpos layout). */
    assert_int_equal(system("rm -rf " TMP "/broken && mkdir -p " TMP "/broken/glsl && "
                            "ln -s \"$PWD/cli/viewer\" " TMP "/broken/viewer && ln -s \"$PWD/runtimes/web\" " TMP "/broken/web && "
                            "sed 's/cb_texel_xy(row, bone \\* CB_TEXELS_PER_BONE + k)/"
                            "cb_texel_xy(row, bone * CB_TEXELS_PER_BONE + (k ^ 1))/' runtimes/glsl/crowdbake_palette.glsl > "
                            TMP "/broken/glsl/crowdbake_palette.glsl && "
                            "! cmp -s runtimes/glsl/crowdbake_palette.glsl " TMP "/broken/glsl/crowdbake_palette.glsl"),
                     0);
    char env[2 * PATH_MAX], cwd[PATH_MAX];
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(env, sizeof env, "CROWDBAKE_WEB=%s/" TMP "/broken", cwd);
    assert_int_equal(run_view(env, TMP "/cache-broken", TMP "/broken.png", ""), 0);
    double mismatch = number("palette_vs_vat_mismatch");
    printf("  broken shader: palette and VAT silhouettes differ on %.0f%% of the covered pixels\n", 100 * mismatch);
    assert_true(mismatch > 0.2);
}

/* The viewer is a local server: only requests that name it (127.0.0.1, localhost or [::1] with
 * its port) are answered, so a page elsewhere cannot read the models through DNS rebinding (its
 * own name pointed at 127.0.0.1: the browser then sends Host: that name); folders are not listed. */
static view_server server; /* stopped by the teardown too, when a check fails half-way */

static int stop_server(void **state)
{
    (void)state;
    if (server.pid > 0) view_stop(&server);
    server.pid = 0;
    return 0;
}

static void test_view_answers_only_its_own_host_and_lists_nothing(void **state)
{
    (void)state;
    char fish[PATH_MAX], host[64], answer[1 << 16];
    snprintf(fish, sizeof fish, "%s/fish.glb", samples_dir());
    assert_int_equal(system("rm -rf " TMP "/host && mkdir -p " TMP "/host"), 0);
    view_server *s = &server;
    if (view_start(s, crowdbake_exe(), fish, TMP "/host/cache", NULL)) fail_msg("no URL from crowdbake view:\n%s", s->printed);
    static const char *const local[] = {"127.0.0.1", "localhost", "[::1]", "LocalHost"};
    for (size_t i = 0; i < COUNT_OF(local); ++i) {
        snprintf(host, sizeof host, "%s:%u", local[i], s->port);
        assert_int_equal(http_get(s->port, "/viewer/viewer.html", host, answer, sizeof answer), 0);
        if (strncmp(answer, "HTTP/1.0 200 ", 13) || !strstr(http_body(answer), "<canvas id=\"view\""))
            fail_msg("Host %s: %.300s", host, answer);
    }
    /* A rebinding page's name, another port, the right name on no port, no Host at all. */
    char other_port[64], bare[64];
    snprintf(other_port, sizeof other_port, "127.0.0.1:%u", s->port + 1);
    snprintf(bare, sizeof bare, "localhost");
    const char *const refused[] = {"attacker.example:80", "attacker.example", other_port, bare, "127.0.0.1.nip.io", NULL};
    for (size_t i = 0; i < COUNT_OF(refused); ++i) {
        assert_int_equal(http_get(s->port, "/view.json", refused[i], answer, sizeof answer), 0);
        const char *body = http_body(answer);
        if (strncmp(answer, "HTTP/1.0 403 ", 13) || !strstr(body, "crowdbake view: Host '") ||
            strchr(body, '\n') != body + strlen(body) - 1 || strstr(body, "\"types\""))
            fail_msg("Host %s: %.300s", refused[i] ? refused[i] : "(none)", answer);
    }
    /* Folders: 404 with one line, never a listing of the site, the web files or the models. */
    snprintf(host, sizeof host, "127.0.0.1:%u", s->port);
    static const char *const folders[] = {"/", "/web/", "/viewer/", "/glsl/", "/models/fish/", "/data/", "/web"};
    for (size_t i = 0; i < COUNT_OF(folders); ++i) {
        assert_int_equal(http_get(s->port, folders[i], host, answer, sizeof answer), 0);
        if (strncmp(answer, "HTTP/1.0 404 ", 13) || strstr(answer, "Directory listing") || strstr(answer, "viewer.html\""))
            fail_msg("GET %s: %.300s", folders[i], answer);
    }
    /* The files themselves are still served. */
    assert_int_equal(http_get(s->port, "/view.json", host, answer, sizeof answer), 0);
    if (strncmp(answer, "HTTP/1.0 200 ", 13) || !strstr(http_body(answer), "\"name\": \"fish\"")) fail_msg("%.300s", answer);
    assert_int_equal(view_stop(s), 0);
    s->pid = 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_view_answers_only_its_own_host_and_lists_nothing, stop_server),
        cmocka_unit_test(test_view_shows_a_moving_herd_of_cows),
        cmocka_unit_test(test_a_broken_palette_shader_is_caught),
        cmocka_unit_test(test_view_shows_a_vat_beside_timed_rows),
    };
    return cmocka_run_group_tests_name("view", tests, NULL, NULL);
}
