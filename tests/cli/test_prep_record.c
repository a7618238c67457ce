/* test_prep_record.c - a catalog rebuild decides "up to date" from each type's record
 * (cli/roster/roster_cache.h) without loading or sampling, and says exactly what a rebuild from
 * the models would: the same manifest bytes, depfile and report. Any change to a type's files,
 * a damaged record or a missing palette sends that type (and only it) back to its model. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include "catalog/catalog_toml.h"
#include "report/report.h"
#include "roster/roster.h"

#define TMP TEST_TMP "/prep_record"

typedef struct run_result {
    char *manifest, *depfile, *report;
    bool from_record[8];
    cb_type_outcome outcome[8];
    uint32_t count;
    bool manifest_written;
} run_result;

static void free_result(run_result *r)
{
    free(r->manifest), free(r->depfile), free(r->report);
    memset(r, 0, sizeof *r);
}

/* One bake of the catalog through the library; what it wrote and said. */
static void bake(const char *catalog, run_result *res)
{
    cb_catalog cat;
    cb_error err = {0};
    if (cb_catalog_load(catalog, &cat, &err)) fail_msg("%s", err.message);
    cb_roster_options opt = {0};
    opt.jobs = 2;
    opt.depfile = TMP "/roster.d";
    cb_roster r;
    if (cb_roster_bake(&cat, &opt, &r, &err)) fail_msg("%s", err.message);
    memset(res, 0, sizeof *res);
    res->count = r.type_count;
    res->manifest_written = r.manifest_written;
    for (uint32_t i = 0; i < r.type_count && i < 8; ++i) {
        res->from_record[i] = r.types[i].prepared_from_record;
        res->outcome[i] = r.types[i].outcome;
    }
    size_t size = 0;
    char *buf = NULL;
    FILE *mem = open_memstream(&buf, &size);
    cb_report rep;
    assert_int_equal(cb_report_build(&cat, &r, &rep, &err), CB_OK);
    cb_report_paragraph(mem, &rep);
    cb_report_free(&rep);
    fclose(mem);
    res->report = buf;
    res->manifest = read_whole_file(TMP "/out/roster.json", &size);
    res->depfile = read_whole_file(TMP "/roster.d", &size);
    assert_non_null(res->manifest);
    assert_non_null(res->depfile);
    cb_roster_free(&r);
    cb_catalog_free(&cat);
}

static void copy_file(const char *from, const char *to)
{
    char cmd[2 * PATH_MAX + 16];
    snprintf(cmd, sizeof cmd, "cp '%s' '%s'", from, to);
    assert_int_equal(system(cmd), 0);
}

/* Types by name: bird (own copy of a model), fox (.gltf + external .bin), goat (with a LOD),
 * sheep (shares goat's palette). */
enum { BIRD, FOX, GOAT, SHEEP, TYPES };

static void test_rebuild_from_records_says_what_the_models_say(void **state)
{
    (void)state;
    char samples[PATH_MAX], fox_dir[PATH_MAX], path[PATH_MAX + 64], text[3 * PATH_MAX + 1024];
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    assert_non_null(realpath(samples_dir(), samples));
    shared_path(path, sizeof path, "assets/derived-fox/separate");
    assert_non_null(realpath(path, fox_dir));
    snprintf(path, sizeof path, "%s/bird.glb", samples);
    copy_file(path, TMP "/bird.glb");
    snprintf(path, sizeof path, "%s/Fox.gltf", fox_dir);
    copy_file(path, TMP "/Fox.gltf");
    snprintf(path, sizeof path, "%s/Fox.bin", fox_dir);
    copy_file(path, TMP "/Fox.bin");
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"out\"\nfps = 30\n"
             "[animal.bird]\nmodel = \"bird.glb\"\nfps = 24\n\n"
             "[animal.fox]\nmodel = \"Fox.gltf\"\nstates = { idle = [\"survey\"], wander = [\"walk\"], flee = [\"run\"] }\n"
             "default_state = \"wander\"\n\n"
             "[animal.goat]\nmodel = \"%s/quadruped.glb\"\nlods = [\"%s/quadruped_lod1.glb\"]\n"
             "states = { idle = [\"idle\"], wander = [\"walk\"], flee = [\"run\"] }\ndefault_state = \"wander\"\n\n"
             "[animal.sheep]\nmodel = \"%s/quadruped.glb\"\nstates = { rest = [\"idle\"], walk = [\"walk\"], run = [\"run\"] }\n",
             samples, samples, samples);
    write_text(TMP "/catalog.toml", text);

    run_result cold, warm, again;
    bake(TMP "/catalog.toml", &cold);
    assert_int_equal(cold.count, TYPES);
    for (int i = 0; i < TYPES; ++i) assert_false(cold.from_record[i]);
    assert_int_equal(cold.outcome[FOX], CB_TYPE_BAKED);

    /* Nothing changed: every type from its record, and every byte said is the same. */
    bake(TMP "/catalog.toml", &warm);
    for (int i = 0; i < TYPES; ++i) assert_true(warm.from_record[i]);
    assert_int_equal(warm.outcome[FOX], CB_TYPE_UP_TO_DATE);
    assert_int_equal(warm.outcome[SHEEP], CB_TYPE_SHARED);
    assert_false(warm.manifest_written);
    assert_string_equal(warm.manifest, cold.manifest);
    assert_string_equal(warm.depfile, cold.depfile);
    assert_string_equal(warm.report, cold.report);
    free_result(&warm);

    /* Another model in bird's file, and one changed byte of Fox's external buffer (the lowest
     * bit of its first vertex's x): those two go back to their models; the others do not. */
    snprintf(path, sizeof path, "%s/fish.glb", samples);
    copy_file(path, TMP "/bird.glb");
    FILE *bin = fopen(TMP "/Fox.bin", "r+b");
    assert_non_null(bin);
    int first = fgetc(bin);
    assert_int_equal(fseek(bin, 0, SEEK_SET), 0);
    fputc(first ^ 0x01, bin);
    fclose(bin);
    bake(TMP "/catalog.toml", &again);
    assert_false(again.from_record[BIRD]);
    assert_false(again.from_record[FOX]);
    assert_true(again.from_record[GOAT]);
    assert_true(again.from_record[SHEEP]);
    assert_int_equal(again.outcome[BIRD], CB_TYPE_BAKED);
    assert_int_equal(again.outcome[FOX], CB_TYPE_BAKED); /* the bytes are in the palette's input hash */
    assert_int_equal(again.outcome[GOAT], CB_TYPE_UP_TO_DATE);
    free_result(&again);

    /* A damaged record is not trusted: goat is prepared from its model, still up to date. */
    FILE *rec = fopen(TMP "/out/.goat.prep", "r+b");
    assert_non_null(rec);
    assert_int_equal(fseek(rec, 60, SEEK_SET), 0);
    int byte = fgetc(rec);
    assert_int_equal(fseek(rec, 60, SEEK_SET), 0);
    fputc(byte ^ 0x10, rec);
    fclose(rec);
    bake(TMP "/catalog.toml", &again);
    assert_false(again.from_record[GOAT]);
    assert_int_equal(again.outcome[GOAT], CB_TYPE_UP_TO_DATE);
    assert_true(again.from_record[FOX]);
    free_result(&again);

    /* A palette that is gone is baked from the model, with the same bytes as before. */
    size_t size_before, size_after;
    char *fox_before = read_whole_file(TMP "/out/fox.pal", &size_before);
    assert_int_equal(unlink(TMP "/out/fox.pal"), 0);
    bake(TMP "/catalog.toml", &again);
    assert_false(again.from_record[FOX]);
    assert_int_equal(again.outcome[FOX], CB_TYPE_BAKED);
    char *fox_after = read_whole_file(TMP "/out/fox.pal", &size_after);
    assert_true(size_before == size_after && memcmp(fox_before, fox_after, size_before) == 0);
    free(fox_before), free(fox_after);
    free_result(&again);
    free_result(&cold);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rebuild_from_records_says_what_the_models_say),
    };
    return cmocka_run_group_tests_name("prep_record", tests, NULL, NULL);
}
