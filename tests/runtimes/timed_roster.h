/* timed_roster.h - the rosters the engine runtimes' herd tests (Unity, Unreal, Godot) read: a Cow catalog baked with
 * the [bake] keys a test gives (untimed, or local and timed rows); a roster with timed states (docs/roster.md,
 * "Filling per-instance data"): samples/catalog.toml baked with local, timed rows, as runtimes/web/test/
 * roster.test.mjs's last test bakes it; a copy of it with one timed state damaged; and the checks every runtime's
 * instance numbers must pass. Include after testutil.h. */
#ifndef CROWDBAKE_TESTS_TIMED_ROSTER_H
#define CROWDBAKE_TESTS_TIMED_ROSTER_H

#include <math.h>
#include <stdlib.h>

static inline void timed_roster_run(const char *cmd)
{
    static char log[16384];
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s:\n%s", cmd, log);
}

/* TOML (a path ending in .toml), a catalog of the shared Cow with the [bake] keys BAKE_KEYS (out_dir among them) and
 * the animal keys ANIMAL_KEYS (its states, ...), written and baked: the bake's exit status (0 when it baked). Not a
 * cmocka assertion, so a group's setup can call it. */
static inline int bake_cow_catalog(const char *toml, const char *bake_keys, const char *animal_keys)
{
    char rel[1024], cmd[2 * 4096 + 64];
    shared_path(rel, sizeof rel, "assets/quaternius-cow/Cow.glb");
    char *cow = realpath(rel, NULL);
    FILE *f = cow ? fopen(toml, "w") : NULL;
    if (f) fprintf(f, "[bake]\n%s\n\n[animal.cow]\nmodel = \"%s\"\n%s\n", bake_keys, cow, animal_keys);
    free(cow);
    if (!f || fclose(f) != 0) return -1;
    snprintf(cmd, sizeof cmd, "%s bake %s -q 2>&1", crowdbake_exe(), toml);
    return system(cmd);
}

/* samples/catalog.toml with bone_space = "local" and timed_rows = "on", baked into DIR/timed (DIR/timed/roster.json). */
static inline void bake_timed_roster(const char *dir)
{
    char cmd[4096], *samples = realpath(samples_dir(), NULL);
    assert_non_null(samples);
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && sed -e 's|^out_dir = \"../build/roster\"|out_dir = \"timed\"\\nbone_space = \"local\"\\ntimed_rows = \"on\"|' "
             "-e 's|\"../build/samples/|\"%s/|g' samples/catalog.toml > %s/timed.toml && %s bake %s/timed.toml -q 2>&1",
             dir, samples, dir, crowdbake_exe(), dir);
    free(samples);
    timed_roster_run(cmd);
}

/* DIR/timed/roster.json with the instance of a state of the first timed clip (`s`) changed by the Python statement EDIT,
 * into OUT. */
static inline void damage_timed_roster(const char *dir, const char *edit, const char *out)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "python3 -c 'import json, sys\n"
             "doc = json.load(open(sys.argv[1]))\n"
             "t = next(t for t in doc[\"types\"].values() if any(\"timed_rows\" in c for c in t[\"clips\"]))\n"
             "clip = next(c[\"name\"] for c in t[\"clips\"] if \"timed_rows\" in c)\n"
             "s = next(s[\"instance\"] for s in t[\"states\"].values() if s[\"clip\"] == clip)\n"
             "%s\n"
             "json.dump(doc, open(sys.argv[2], \"w\"))' %s/timed/roster.json %s 2>&1",
             edit, dir, out);
    timed_roster_run(cmd);
}

/* The two damages every reader refuses, and the words of its one-line error (crowdbake_pal.mjs readRoster's). */
static const struct { const char *edit, *field, *words; } timed_roster_damages[] = {
    {"s[\"frame_count\"] += 1", ".instance.frame_count: ", " cells, got "},
    {"s[\"rate\"] = abs(s[\"rate\"]); s[\"rate_per_speed\"] = abs(s[\"rate_per_speed\"])", ".instance.rate: ",
     "has timed rows: rate and rate_per_speed must be negative"},
};

/* A reader's error for a damaged timed state: one line, naming the field, in readRoster's words. */
static inline void check_timed_refusal(const char *log, size_t damage)
{
    const char *newline = strchr(log, '\n');
    if (!strstr(log, timed_roster_damages[damage].field) || !strstr(log, timed_roster_damages[damage].words) ||
        (newline && newline[1]))
        fail_msg("damaged (%s): %s", timed_roster_damages[damage].edit, log);
    printf("  damaged (%s): %s", timed_roster_damages[damage].edit, log);
}

/* A runtime's lines "D type state cells cell_rate map_rows frame_count rate rate_per_speed still4 moving4" (cells 0: an
 * untimed clip; still: instance 1 standing, moving: at speed 2): a timed state counts its clip's cells and plays at
 * z < 0, -1e-30 standing still when it follows the speed (rate_per_speed != 0), -|rate_per_speed| x 2 moving, else its
 * rate; an untimed state as ever (rate_per_speed x 2, or rate). Prints and checks the counts. */
static inline void check_timed_instance_lines(const char *path, const char *runtime)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[1024], type[64], name[64];
    unsigned timed = 0, timed_synced = 0, synced = 0;
    while (fgets(line, sizeof line, f)) {
        int cells, map_rows, frames;
        float cell_rate, rate, per_speed, s[4], m[4];
        if (sscanf(line, "D %63s %63s %d %f %d %d %f %f %f %f %f %f %f %f %f %f", type, name, &cells, &cell_rate, &map_rows, &frames,
                   &rate, &per_speed, &s[0], &s[1], &s[2], &s[3], &m[0], &m[1], &m[2], &m[3]) != 16)
            fail_msg("%s: not a D line: %s", runtime, line);
        if (!(s[0] == m[0] && s[1] == frames && m[1] == frames && s[3] == m[3] && s[3] >= 0 && s[3] < 1))
            fail_msg("%s: %s", runtime, line);
        float magnitude = per_speed != 0 ? fabsf(per_speed) * 2 : fabsf(rate);
        if (cells) {
            ++timed;
            timed_synced += per_speed != 0;
            if (!(abs(frames) == cells && cell_rate > 0 && map_rows >= 1 && rate < 0 && per_speed <= 0 && s[2] < 0 && m[2] < 0 &&
                  s[2] == (per_speed != 0 ? -1e-30f : rate) && fabsf(m[2] + magnitude) <= 1e-6f * magnitude))
                fail_msg("%s: timed state %s %s: %s", runtime, type, name, line);
        } else {
            synced += per_speed != 0;
            if (!(rate >= 0 && per_speed >= 0 && s[2] == (per_speed != 0 ? 0 : rate) && fabsf(m[2] - magnitude) <= 1e-6f * magnitude))
                fail_msg("%s: state %s %s: %s", runtime, type, name, line);
        }
    }
    fclose(f);
    printf("  %s, timed catalog: %u timed states (%u follow the speed: still -1e-30), %u untimed that follow it\n", runtime, timed,
           timed_synced, synced);
    assert_true(timed > 0 && timed_synced > 0);
}

#endif
