/* cmd_view.c - `crowdbake view MODEL|PALETTE|catalog.toml`: bakes what is missing into a cache
 * folder, then serves the web viewer (cli/viewer/viewer.html) on 127.0.0.1 with Python's http.server
 * (cli/viewer/serve.py) and prints its URL. Thin: the bake is the roster's, the VAT is `vat`'s, the
 * page is cli/viewer's. The cache folder becomes the site: viewer/, web/ and glsl/ are links to
 * the viewer, the web runtime (runtimes/web) and the GLSL (runtimes/glsl), data/ to the roster's folder (or the palette's), models/TYPE/ to each model's
 * folder, vat/TYPE.exr the VATs, view.json what the page shows. */
#define _DEFAULT_SOURCE
#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "catalog/catalog_toml.h"
#include "roster/roster.h"
#include "cli.h"

const char cmd_view_usage[] =
    "usage: crowdbake view MODEL|catalog.toml [--port N] [--open] [--cache DIR] [-q] [-v]\n"
    "       crowdbake view PALETTE.pal --model MODEL [--port N] [--open] [--cache DIR] [-q] [-v]\n\n"
    "Shows a herd in the browser: bakes what is missing (a model gets a catalog of one type with a\n"
    "state per clip, root motion in place; a catalog is baked as 'bake' does), bakes a VAT of the same\n"
    "frames to compare, then serves the viewer on 127.0.0.1 (port N, default any free port) with\n"
    "Python's http.server and prints its URL: a local server, it answers only requests for\n"
    "127.0.0.1, localhost or [::1] with its port (403 otherwise) and lists no folders. --open starts a browser ($BROWSER, else xdg-open).\n"
    "The viewer: the herd walking about, a button per state (cross-fading), up to 100,000\n"
    "instances in one draw call, frame time and draw calls, palette and VAT side by side with the\n"
    "VRAM of each. Ctrl-C stops the server. The cache is DIR (default\n"
    "$XDG_CACHE_HOME/crowdbake/view/NAME-HASH). The web files are found beside the executable:\n"
    "BIN/../share/crowdbake/{viewer,web,glsl} where 'make install' puts them, or the source tree's\n"
    "cli/viewer, runtimes/web and runtimes/glsl for build/crowdbake; CROWDBAKE_WEB=DIR names another\n"
    "folder laid out as the installed one (DIR/viewer, DIR/web, DIR/glsl).\n";

typedef struct view_paths {
    char cache[PATH_MAX], site[PATH_MAX + 8], viewer[PATH_MAX + 32], web[PATH_MAX + 32], glsl[PATH_MAX + 32];
    cli_output out; /* -q: no bake log; -v: what is baked and linked where */
} view_paths;

static int fail_io(const char *what, const char *path)
{
    fprintf(stderr, "crowdbake: view: %s %s: %s\n", what, path, strerror(errno));
    return CLI_EXIT_IO;
}

static int mkdirs(const char *path)
{
    char p[PATH_MAX];
    snprintf(p, sizeof p, "%s", path);
    for (char *s = p + 1; *s; ++s)
        if (*s == '/') {
            *s = 0;
            if (mkdir(p, 0755) && errno != EEXIST) return -1;
            *s = '/';
        }
    return mkdir(p, 0755) && errno != EEXIST ? -1 : 0;
}

/* The folder part of `path` ("." for a bare name). */
static void dir_of(const char *path, char *out, size_t size)
{
    snprintf(out, size, "%s", path);
    char *slash = strrchr(out, '/');
    if (slash) *slash = 0;
    else snprintf(out, size, ".");
}

/* site/NAME -> target, replacing an older link. */
static int link_into_site(const view_paths *v, const char *name, const char *target)
{
    char at[2 * PATH_MAX + 16], abs[PATH_MAX];
    snprintf(at, sizeof at, "%s/%s", v->site, name);
    char *slash = strrchr(at, '/');
    *slash = 0;
    if (mkdirs(at)) return fail_io("cannot create", at);
    *slash = '/';
    if (!realpath(target, abs)) return fail_io("cannot find", target);
    unlink(at);
    if (symlink(abs, at)) return fail_io("cannot link", at);
    return 0;
}

/* Where the viewer, the web runtime and the GLSL are: one layout, rooted at `root`. */
typedef struct web_layout {
    const char *root, *viewer, *web, *glsl;
} web_layout;

static void set_web_layout(view_paths *v, const char *base, const web_layout *l)
{
    snprintf(v->viewer, sizeof v->viewer, "%s/%s%s", base, l->root, l->viewer);
    snprintf(v->web, sizeof v->web, "%s/%s%s", base, l->root, l->web);
    snprintf(v->glsl, sizeof v->glsl, "%s/%s%s", base, l->root, l->glsl);
}

/* $CROWDBAKE_WEB (laid out as installed), else the installed files (BIN/../share/crowdbake, as
 * `make install` lays them out), else the source tree whose build folder holds the executable
 * (build/crowdbake, build/asan/crowdbake: one or two levels up). */
static void find_web_folders(view_paths *v)
{
    static const web_layout installed = {"", "viewer", "web", "glsl"};
    const char *env = getenv("CROWDBAKE_WEB");
    if (env) {
        set_web_layout(v, env, &installed);
        return;
    }
    char exe[PATH_MAX], probe[PATH_MAX + 64];
    cli_executable(exe, sizeof exe);
    char *slash = strrchr(exe, '/');
    if (slash) *slash = 0;
    static const web_layout beside[] = {{"../share/crowdbake/", "viewer", "web", "glsl"},
                                        {"../", "cli/viewer", "runtimes/web", "runtimes/glsl"},
                                        {"../../", "cli/viewer", "runtimes/web", "runtimes/glsl"},
                                        {"../../../", "cli/viewer", "runtimes/web", "runtimes/glsl"}};
    for (size_t i = 0; i < sizeof beside / sizeof beside[0]; ++i) {
        set_web_layout(v, exe, &beside[i]);
        snprintf(probe, sizeof probe, "%s/viewer.html", v->viewer);
        if (!access(probe, R_OK)) return;
    }
    set_web_layout(v, exe, &beside[0]); /* named in the error */
}

static int find_web(view_paths *v)
{
    find_web_folders(v);
    char probe[PATH_MAX + 128];
    const struct { const char *dir, *file, *why; } need[] = {
        {v->viewer, "viewer.html", "not a crowdbake viewer folder"},
        {v->viewer, "serve.py", "not a crowdbake viewer folder"},
        {v->web, "node_modules/three/build/three.module.js", "three.js is not installed"},
        {v->glsl, "crowdbake_palette.glsl", "not a crowdbake GLSL folder"}};
    for (size_t i = 0; i < sizeof need / sizeof need[0]; ++i) {
        snprintf(probe, sizeof probe, "%s/%s", need[i].dir, need[i].file);
        if (access(probe, R_OK)) {
            fprintf(stderr, "crowdbake: view: %s is missing: %s (in the source tree run 'make web', which installs "
                            "runtimes/web/node_modules from its package-lock; 'make install' installs them with the "
                            "command; or set CROWDBAKE_WEB=DIR to a folder laid out as PREFIX/share/crowdbake)\n",
                    probe, need[i].why);
            return CLI_EXIT_IO;
        }
    }
    return 0;
}

/* NAME-HASH under $XDG_CACHE_HOME/crowdbake/view (or ~/.cache), from the input's real path. */
static void default_cache(const char *input, const char *name, char *out, size_t size)
{
    char abs[PATH_MAX];
    if (!realpath(input, abs)) snprintf(abs, sizeof abs, "%s", input);
    uint64_t h = 1469598103934665603ull; /* FNV-1a */
    for (const char *s = abs; *s; ++s) h = (h ^ (unsigned char)*s) * 1099511628211ull;
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    if (xdg && *xdg) snprintf(out, size, "%s/crowdbake/view/%s-%08llx", xdg, name, (unsigned long long)(h & 0xffffffffu));
    else snprintf(out, size, "%s/.cache/crowdbake/view/%s-%08llx", home ? home : "/tmp", name, (unsigned long long)(h & 0xffffffffu));
}

/* A type or state name from a file or clip name: after any "Armature|", lower case, [a-z0-9_]. */
static void plain_name(const char *from, char *out, size_t size)
{
    const char *bar = strrchr(from, '|'), *slash = strrchr(from, '/');
    from = bar ? bar + 1 : slash ? slash + 1 : from;
    size_t n = 0;
    for (; *from && *from != '.' && n + 1 < size; ++from) out[n++] = isalnum((unsigned char)*from) ? (char)tolower(*from) : '_';
    out[n] = 0;
    if (!n) snprintf(out, size, "model");
}

/* A catalog of one type for a model: a state per clip (keyword: the clip's full name), root
 * motion in place (the viewer moves the herd), written into the cache. */
static int write_model_catalog(const char *model_path, const cb_limits *limits, const char *type, const char *cache,
                               char *catalog, size_t size)
{
    cb_error err = {0};
    cb_model *m = cli_load_model(NULL, model_path, limits, &err);
    if (!m) return cli_report(&err);
    char abs[PATH_MAX], state[128], default_state[128] = "";
    if (!realpath(model_path, abs)) snprintf(abs, sizeof abs, "%s", model_path);
    snprintf(catalog, size, "%s/catalog.toml", cache);
    FILE *f = fopen(catalog, "w");
    if (!f) return cb_model_free(m), fail_io("cannot write", catalog);
    fprintf(f, "# written by crowdbake view for %s\n[bake]\nout_dir = \"data\"\nroot_motion = \"in-place\"\n\n[animal.%s]\n"
               "model = \"%s\"\nstates = { ", model_path, type, abs);
    uint32_t written = 0;
    for (uint32_t i = 0; i < m->animation_count; ++i) {
        const char *clip = m->animations[i].name;
        bool skipped = false;
        for (uint32_t k = 0; k < m->skipped_clip_count; ++k) skipped |= strcmp(m->skipped_clips[k].name, clip) == 0;
        if (skipped || strchr(clip, '"') || strchr(clip, '\\')) continue;
        plain_name(clip, state, sizeof state);
        fprintf(f, "%s\"%s\" = [\"%s\"]", written++ ? ", " : "", state, clip);
        if (!default_state[0] || strcmp(state, "walk") == 0) snprintf(default_state, sizeof default_state, "%s", state);
    }
    fprintf(f, " }\ndefault_state = \"%s\"\n", default_state);
    cb_model_free(m);
    if (fclose(f)) return fail_io("cannot write", catalog);
    if (!written) {
        fprintf(stderr, "crowdbake: view: %s has no clip to play\n", model_path);
        return CLI_EXIT_INPUT;
    }
    return 0;
}

/* A VAT of a type's frames into site/vat/TYPE.exr (uncompressed: the page reads it as is),
 * unless one newer than the palette is there: the palette's clips at their own rates (`vat
 * --like`), so the VAT's frames line up with the palette's rows whatever rate each clip was
 * baked at. Not for a type that renames its clips (the palette's names are not the model's) or
 * writes no .pal. */
static bool bake_vat(const view_paths *v, const cb_roster_type *t, const char *palette)
{
    const cb_bake_settings *b = &t->animal->bake;
    if (t->animal->clips || !(b->formats & CB_FORMAT_PAL)) {
        printf("  %-16s no VAT (its catalog entry lists or renames its clips, or writes no .pal to take them from)\n",
               t->animal->name);
        return false;
    }
    char out[PATH_MAX + 192], max[32];
    snprintf(out, sizeof out, "%s/vat", v->site);
    if (mkdirs(out)) return fail_io("cannot create", out), false;
    snprintf(out, sizeof out, "%s/vat/%s.exr", v->site, t->animal->name);
    struct stat so, sp;
    if (!stat(out, &so) && !stat(palette, &sp) && so.st_mtime >= sp.st_mtime) return true;
    snprintf(max, sizeof max, "%u", b->max_texture_size);
    char *argv[] = {"vat", (char *)t->animal->model, "-o", out, "--like", (char *)palette, "--max-texture-size", max,
                    "--root-motion", (char *)cb_root_motion_name(b->root_motion),
                    "--exr-compression", "none", NULL};
    printf("  %-16s VAT: ", t->animal->name);
    fflush(stdout);
    return cmd_vat(12, argv) == 0;
}

/* Bakes the catalog, links its files into the site and writes view.json. */
static int prepare_catalog(const view_paths *v, const char *catalog_path)
{
    cb_error err = {0};
    cb_catalog cat;
    if (cb_catalog_load(catalog_path, &cat, &err)) return cli_report(&err);
    cb_roster_options opt = {0};
    opt.setting_name = cli_setting_flag;
    opt.jobs = 1;
    opt.log = v->out.quiet ? NULL : stdout;
    cli_verbose(&v->out, "baking %s into %s", catalog_path, v->cache);
    cb_roster r;
    int rc = cb_roster_bake(&cat, &opt, &r, &err);
    if (rc && r.failed < r.type_count) rc = 0; /* show the types that baked; the log named the others */
    char json[PATH_MAX + 32], name[PATH_MAX + 64], dir[PATH_MAX];
    snprintf(json, sizeof json, "%s/view.json", v->site);
    FILE *f = rc ? NULL : fopen(json, "w");
    if (!rc && !f) rc = fail_io("cannot write", json);
    dir_of(r.manifest_path, dir, sizeof dir);
    if (f && (rc = link_into_site(v, "data", dir))) f = (fclose(f), NULL);
    if (f) fprintf(f, "{\"roster\": \"data/%s\", \"types\": [", strrchr(r.manifest_path, '/') ? strrchr(r.manifest_path, '/') + 1 : r.manifest_path);
    for (uint32_t i = 0, n = 0; f && i < r.type_count; ++i) {
        const cb_roster_type *t = &r.types[i];
        if (t->outcome == CB_TYPE_FAILED) continue;
        snprintf(name, sizeof name, "models/%s", t->animal->name);
        dir_of(t->animal->model, dir, sizeof dir);
        if ((rc = link_into_site(v, name, dir))) break;
        const char *base = strrchr(t->animal->model, '/') ? strrchr(t->animal->model, '/') + 1 : t->animal->model;
        bool vat = bake_vat(v, t, roster_output_path(&r.types[t->owner], CB_FORMAT_PAL));
        fprintf(f, "%s\n  {\"name\": \"%s\", \"model\": \"models/%s/%s\", \"vat\": %s%s%s%s}", n++ ? "," : "", t->animal->name,
                t->animal->name, base, vat ? "\"vat/" : "null", vat ? t->animal->name : "", vat ? ".exr" : "", vat ? "\"" : "");
    }
    if (f) fprintf(f, "\n]}\n");
    if (f && fclose(f)) rc = fail_io("cannot write", json);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
    return rc ? (err.status ? cli_report(&err) : rc) : 0;
}

/* A palette and its model: no roster, the page makes a state of each clip. */
static int prepare_palette(const view_paths *v, const char *pal, const char *model)
{
    char dir[PATH_MAX], json[PATH_MAX + 32];
    dir_of(pal, dir, sizeof dir);
    int rc = link_into_site(v, "data", dir);
    dir_of(model, dir, sizeof dir);
    if (rc || (rc = link_into_site(v, "models/model", dir))) return rc;
    snprintf(json, sizeof json, "%s/view.json", v->site);
    FILE *f = fopen(json, "w");
    if (!f) return fail_io("cannot write", json);
    const char *pb = strrchr(pal, '/') ? strrchr(pal, '/') + 1 : pal, *mb = strrchr(model, '/') ? strrchr(model, '/') + 1 : model;
    fprintf(f, "{\"roster\": null, \"types\": [{\"name\": \"%s\", \"palette\": \"data/%s\", \"model\": \"models/model/%s\", "
               "\"vat\": null}]}\n", pb, pb, mb);
    return fclose(f) ? fail_io("cannot write", json) : 0;
}

/* Binds 127.0.0.1:port (0: any free one); the server inherits the socket. */
static int listen_on(unsigned port, unsigned *bound)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    int one = 1;
    if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) || bind(fd, (struct sockaddr *)&a, sizeof a) ||
        listen(fd, 64) || getsockname(fd, (struct sockaddr *)&a, &len)) {
        fprintf(stderr, "crowdbake: view: cannot listen on 127.0.0.1:%u: %s (try another --port)\n", port, strerror(errno));
        if (fd >= 0) close(fd);
        return -1;
    }
    *bound = ntohs(a.sin_port);
    return fd;
}

static pid_t spawn(char *const argv[])
{
    pid_t pid = fork();
    if (pid == 0) {
        signal(SIGINT, SIG_DFL);
        execvp(argv[0], argv);
        fprintf(stderr, "crowdbake: view: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    return pid;
}

/* The server's pid, for the signal handler: Ctrl-C in a terminal reaches both processes, a
 * `kill -INT` only this one, which passes it on. The one piece of static state: a handler has
 * nowhere else to look. */
static volatile pid_t server_pid;

static void stop_server(int sig)
{
    (void)sig;
    if (server_pid > 0) kill(server_pid, SIGINT);
}

/* Serves the site until Ctrl-C (or the server stops); 0 when it was stopped by Ctrl-C. */
static int serve(const view_paths *v, unsigned port, bool open_browser)
{
    unsigned bound = 0;
    int fd = listen_on(port, &bound);
    if (fd < 0) return CLI_EXIT_IO;
    char fd_text[16], serve_py[PATH_MAX + 48], url[64];
    snprintf(fd_text, sizeof fd_text, "%d", fd);
    snprintf(serve_py, sizeof serve_py, "%s/serve.py", v->viewer);
    snprintf(url, sizeof url, "http://127.0.0.1:%u/viewer/viewer.html", bound);
    printf("crowdbake: serving %s (Ctrl-C stops)\n%s\n", v->site, url);
    fflush(stdout);
    pid_t server = spawn((char *const[]){"python3", serve_py, "--fd", fd_text, "--directory", (char *)v->site, NULL});
    close(fd);
    server_pid = server;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = stop_server;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if (server < 0) return fail_io("cannot start", "python3");
    if (open_browser) {
        const char *browser = getenv("BROWSER");
        pid_t b = spawn((char *const[]){(char *)(browser && *browser ? browser : "xdg-open"), url, NULL});
        (void)b;
    }
    int status = 0;
    while (waitpid(server, &status, 0) < 0 && errno == EINTR) {}
    server_pid = 0;
    bool interrupted = (WIFEXITED(status) && WEXITSTATUS(status) == 0) || (WIFSIGNALED(status) && WTERMSIG(status) == SIGINT);
    if (!interrupted) fprintf(stderr, "crowdbake: view: the server stopped (status %d)\n", status);
    else printf("crowdbake: viewer stopped\n");
    return interrupted ? 0 : CLI_EXIT_IO;
}

int cmd_view(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    view_paths v;
    if (cli_take_output(&argc, argv, &v.out)) return CLI_EXIT_USAGE;
    const char *input = NULL, *port_text = NULL, *cache = NULL, *model = NULL;
    bool open_browser = false, help;
    const cli_option options[] = {{"--port", "N", &port_text, NULL}, {"--open", NULL, NULL, &open_browser},
                                  {"--cache", "DIR", &cache, NULL},  {"--model", "MODEL", &model, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &input, 1, 1, &help);
    if (help) return fputs(cmd_view_usage, stdout), fputs(cli_output_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    unsigned port = 0;
    if (port_text && (!cli_parse_u32(port_text, &port) || port > 65535)) return cli_usage_error("view", "--port wants 0..65535");
    cli_file_kind kind = cli_file_kind_of(input);
    size_t len = strlen(input);
    bool catalog = len > 5 && strcmp(input + len - 5, ".toml") == 0;
    if (kind == CLI_FILE_MISSING) return errno = ENOENT, fail_io("cannot open", input);
    if (kind == CLI_FILE_PAL && !model)
        return cli_usage_error("view", "%s: a palette needs the model it was baked from: crowdbake view %s --model MODEL", input, input);
    if (kind != CLI_FILE_PAL && model) return cli_usage_error("view", "--model goes with a palette only");
    if (!catalog && kind != CLI_FILE_MODEL && kind != CLI_FILE_PAL)
        return cli_usage_error("view", "%s: not a glTF model, a .pal palette or a .toml catalog", input);
    if ((rc = find_web(&v))) return rc;
    char type[128];
    plain_name(input, type, sizeof type);
    if (cache) snprintf(v.cache, sizeof v.cache, "%s", cache);
    else default_cache(input, type, v.cache, sizeof v.cache);
    snprintf(v.site, sizeof v.site, "%s/site", v.cache);
    if (mkdirs(v.site)) return fail_io("cannot create", v.site);
    if ((rc = link_into_site(&v, "viewer", v.viewer)) || (rc = link_into_site(&v, "web", v.web)) ||
        (rc = link_into_site(&v, "glsl", v.glsl)))
        return rc;
    char generated[PATH_MAX + 32];
    if (kind == CLI_FILE_MODEL && (rc = write_model_catalog(input, &limits, type, v.cache, generated, sizeof generated))) return rc;
    if (kind == CLI_FILE_PAL) rc = prepare_palette(&v, input, model);
    else rc = prepare_catalog(&v, kind == CLI_FILE_MODEL ? generated : input);
    return rc ? rc : serve(&v, port, open_browser);
}
