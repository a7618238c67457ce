/* test_pal_file.c - the .pal and .exr files: byte-identical bakes, every kind of corruption
 * rejected by the reader and by `crowdbake inspect`, EXR texels identical to the .pal's. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>
#include <sys/stat.h>
#include <unistd.h>

#include "crowdbake_pal.h"
#include "crowdbake/babylon.h"
#include "crowdbake/exr.h"
#include "crowdbake/ktx2.h"
#include "crowdbake/pal_view.h"
#include "crowdbake/runtime.h"
#include "timed_subset.h"

#define TMP TEST_TMP "/pal_file"

static unsigned char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *d = malloc(*size ? *size : 1);
    assert_int_equal(fread(d, 1, *size, f), *size);
    fclose(f);
    return d;
}

static void write_all(const char *path, const unsigned char *d, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(d, 1, size, f), size);
    fclose(f);
}

/* Global rows unless extra says otherwise: these files are compared with their EXR and older versions' layouts
 * (local rows, the default bake's: test_local_rows.c). */
static void bake(const char *model, const char *out, const char *extra)
{
    char cmd[2048], log[4096];
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s -q --fps 30 %s%s 2>&1", crowdbake_exe(), model, out, extra,
             strstr(extra, "--bone-space") ? "" : " --bone-space global");
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s failed: %s", cmd, log);
}

static int setup(void **state)
{
    (void)state;
    return system("mkdir -p " TMP);
}

static void test_byte_identical_bakes(void **state)
{
    (void)state;
    char fox[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    /* The second bake of each pair runs on another thread count: clips are split across
     * threads, and the bytes must not depend on it. */
    const char *variants[] = {"", "--layout mat4 --precision half", "--zstd", "--precision float --format pal,exr"};
    for (int i = 0; i < 4; ++i) {
        char one[256], two[256];
        snprintf(one, sizeof one, "%s -j 1", variants[i]);
        snprintf(two, sizeof two, "%s -j 3", variants[i]);
        bake(fox, TMP "/a.pal", one);
        bake(fox, TMP "/b.pal", two);
        size_t na, nb;
        unsigned char *a = read_all(TMP "/a.pal", &na), *b = read_all(TMP "/b.pal", &nb);
        assert_int_equal(na, nb);
        assert_memory_equal(a, b, na);
        free(a), free(b);
        if (strstr(variants[i], "exr")) {
            a = read_all(TMP "/a.exr", &na), b = read_all(TMP "/b.exr", &nb);
            assert_int_equal(na, nb);
            assert_memory_equal(a, b, na);
            free(a), free(b);
        }
    }
}

static void test_exr_reads_back_bit_identical_and_opens_in_openexr_tools(void **state)
{
    (void)state;
    char fox[1024], cmd[2048], out[8192];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    const char *precisions[] = {"--precision half", "--precision float", "--precision half --exr-compression zip"};
    for (int i = 0; i < 3; ++i) {
        char extra[256];
        snprintf(extra, sizeof extra, "%s --format pal,exr --max-texture-size 100", precisions[i]); /* wraps */
        bake(fox, TMP "/fox.pal", extra);
        cbpal_file pal;
        char err[256];
        assert_int_equal(cbpal_open(TMP "/fox.pal", CBPAL_VERIFY_CHECKSUM, &pal, err, sizeof err), 0);
        cb_exr_image img;
        cb_error e = {0};
        if (cb_exr_read(TMP "/fox.exr", &img, &e)) fail_msg("%s", e.message);
        assert_true(pal.header.blocks > 1);
        assert_int_equal(img.width, pal.header.width);
        assert_int_equal(img.height, pal.header.height);
        assert_int_equal(img.texel_bytes, pal.texels_size);
        assert_memory_equal(img.texels, pal.texels, pal.texels_size);
        assert_int_equal(img.bones, (int)pal.header.bone_count);
        assert_int_equal(img.blocks, (int)pal.header.blocks);
        cb_exr_image_free(&img);
        cbpal_close(&pal);
    }
    snprintf(cmd, sizeof cmd, "exrheader %s/fox.exr 2>&1", TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "crowdbake.bones"));
    assert_non_null(strstr(out, "crowdbake.clip0.name"));
    assert_non_null(strstr(out, "zip"));
    /* Debian's exrinfo (OpenEXR 3.1.5) exits with an arbitrary status after a good read, so its
     * output is what tells: the file's scanline part and its four channels. */
    snprintf(cmd, sizeof cmd, "exrinfo %s/fox.exr 2>&1", TMP);
    run_command(cmd, out, sizeof out);
    if (!strstr(out, "type: 'scanlineimage'") || !strstr(out, "channels: 4 channels") || strstr(out, "ERROR"))
        fail_msg("exrinfo:\n%s", out);
}

static void test_u16_is_refused_for_exr(void **state)
{
    (void)state;
    char fox[1024], cmd[2048], out[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/x.exr --precision u16 2>&1", crowdbake_exe(), fox, TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_USAGE);
    assert_non_null(strstr(out, "half or float"));
}

/* The reader's message for a damaged copy of `good`, or NULL when it opens. */
static const char *reader_error(const unsigned char *d, size_t size, char *err, size_t err_size)
{
    cbpal_file f;
    if (cbpal_open_memory(d, size, CBPAL_VERIFY_CHECKSUM, &f, err, err_size) == 0) {
        cbpal_close(&f);
        return NULL;
    }
    return err;
}

static void expect_rejected(const unsigned char *d, size_t size, const char *needle, const char *what)
{
    char err[256];
    const char *msg = reader_error(d, size, err, sizeof err);
    if (!msg) fail_msg("%s: the reader accepted it", what);
    if (!strstr(msg, needle)) fail_msg("%s: message '%s' lacks '%s'", what, msg, needle);
    /* crowdbake inspect says the same, with the file name, and exits 4 */
    write_all(TMP "/bad.pal", d, size);
    char cmd[1024], out[1024];
    snprintf(cmd, sizeof cmd, "%s inspect %s/bad.pal 2>&1", crowdbake_exe(), TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT);
    if (!strstr(out, needle) || !strstr(out, "bad.pal")) fail_msg("%s: inspect said '%s'", what, out);
}

static uint64_t rd64(const unsigned char *d) { uint64_t v; memcpy(&v, d, 8); return v; }
static void wr64(unsigned char *d, uint64_t v) { memcpy(d, &v, 8); }
static void wr32(unsigned char *d, uint32_t v) { memcpy(d, &v, 4); }

static void test_corruption_is_rejected(void **state)
{
    (void)state;
    char fox[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    bake(fox, TMP "/good.pal", "");
    size_t size;
    unsigned char *good = read_all(TMP "/good.pal", &size), *d = malloc(size);
    char err[256];
    assert_null(reader_error(good, size, err, sizeof err));
    uint64_t clips = rd64(good + 120), bones = rd64(good + 128), strings = rd64(good + 136), payload = rd64(good + 152);

    /* A flipped bit in each region: the checksum catches what validation cannot. */
    uint64_t regions[][2] = {{64, 0x01}, {clips + 20, 0x10}, {bones + 16, 0x01}, {strings + 1, 0x02}, {payload + 100, 0x40}};
    const char *names[] = {"header", "clip table", "bone table", "strings", "payload"};
    for (int i = 0; i < 5; ++i) {
        memcpy(d, good, size);
        d[regions[i][0]] ^= (unsigned char)regions[i][1];
        expect_rejected(d, size, "checksum mismatch", names[i]);
    }
    /* Truncation at every table boundary, and mid-payload. */
    uint64_t cuts[] = {0, 8, 100, 256, clips, clips + 40, bones, strings, payload, payload + 1, size - 1};
    for (size_t i = 0; i < sizeof cuts / sizeof cuts[0]; ++i) {
        char what[64];
        snprintf(what, sizeof what, "truncated at %llu", (unsigned long long)cuts[i]);
        const char *needle = cuts[i] < 8 ? "wrong magic" : cuts[i] < 256 ? "truncated" : cuts[i] <= clips + 40 ? "clip table"
                           : cuts[i] <= bones ? "bone table" : cuts[i] <= strings ? "string table" : "payload";
        expect_rejected(good, (size_t)cuts[i], needle, what);
    }
    /* A bogus offset and a future version, each with its own message. */
    memcpy(d, good, size);
    wr64(d + 152, payload + 4096 * 1000);
    expect_rejected(d, size, "payload", "bogus payload offset");
    memcpy(d, good, size);
    wr64(d + 120, (uint64_t)1 << 40);
    expect_rejected(d, size, "clip table", "bogus clip offset");
    /* Version 5: Fox's Walk and Run carry travel offsets; their table is checked like the others. */
    assert_int_equal(rd64(good + 192) != 0, 1);
    memcpy(d, good, size);
    wr64(d + 192, size - 3);
    expect_rejected(d, size, "travel offset table", "travel table past the end");
    memcpy(d, good, size);
    wr64(d + 192, 100); /* inside the header */
    expect_rejected(d, size, "travel offset table", "travel table in the header");
    memcpy(d, good, size);
    d[rd64(good + 192) + 5] ^= 0x10;
    expect_rejected(d, size, "checksum mismatch", "travel table");
    memcpy(d, good, size);
    wr32(d + 8, CBPAL_VERSION + 1);
    expect_rejected(d, size, "newer than this reader", "future version");
    memcpy(d, good, size);
    wr32(d + 40, 1u << 30); /* rows */
    expect_rejected(d, size, "inconsistent texture geometry", "bogus rows");
    free(good), free(d);
}

/* Local rows (version 6, flag bit 5): the range table and what bit 5 needs, each refused with its own
 * message before the checksum is looked at. */
static void test_local_corruption_is_rejected(void **state)
{
    (void)state;
    char fox[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    bake(fox, TMP "/local.pal", "--bone-space local");
    size_t size;
    unsigned char *good = read_all(TMP "/local.pal", &size), *d = malloc(size);
    char err[256];
    assert_null(reader_error(good, size, err, sizeof err));
    uint64_t ranges = rd64(good + 200), bones = rd64(good + 128);
    assert_true(ranges >= CBPAL_HEADER_SIZE && ranges % 4 == 0);
    struct { uint64_t at; uint32_t value; int width; const char *needle, *what; } cases[] = {
        {200, 0, 8, "bone range table", "range table offset 0"},
        {200, 100, 8, "bone range table", "range table in the header"},
        {200, (uint32_t)size - 8, 8, "bone range table", "range table past the end"},
        {ranges, 0x7fc00000u, 4, "range", "pos_min NaN"},
        {ranges + 4, 0x7f800000u, 4, "range", "pos_min infinite"},
        {ranges + 12, 0, 4, "range", "scale_max 0"},
        {ranges + 16, 0xff7fffffu, 4, "range", "pos_max below pos_min"},
        {ranges + 28, 1, 4, "range", "reserved word not 0"},
        {8, 5, 4, "flag bit 5 (local rows) in a version 5 file", "bit 5 in a version 5 file"},
        {24, 1, 4, "local rows need qpos and u16 or float", "precision half"},
        {bones + 8, 0, 4, "its own ancestor", "bone 0 its own parent"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(d, good, size);
        if (cases[i].width == 8) wr64(d + cases[i].at, cases[i].value);
        else wr32(d + cases[i].at, cases[i].value);
        expect_rejected(d, size, cases[i].needle, cases[i].what);
    }
    free(good), free(d);
}

/* Fox baked uniform at 30 fps with `options`, its Walk and Run made timed (timed_subset.h: rows kept
 * at intervals of 1, 2 and 3 cells), Survey left untimed, written by the library's writer to `out`.
 * The uniform file stays open in *uniform and its view in *view (timed borrows them): the caller closes them. */
static void write_timed_fox(const char *options, const char *out, cbpal_file *uniform, cb_palette *view, cb_palette *timed)
{
    char fox[1024], err[256];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    bake(fox, TMP "/uniform.pal", options);
    if (cbpal_open(TMP "/uniform.pal", CBPAL_VERIFY_CHECKSUM, uniform, err, sizeof err)) fail_msg("%s", err);
    cb_error e = {0};
    assert_int_equal(cb_palette_view(uniform, view, &e), CB_OK);
    cb_model *m = load_or_fail(fox);
    assert_true(timed_subset_make(uniform, view, 0, 0, timed)); /* borrows the view's bones */
    if (timed_subset_write(out, timed, uniform, m, &e)) fail_msg("%s", e.message);
    cb_model_free(m);
}

/* Timed rows (version 7): written only with a timed clip, read back with the same texels and clip
 * fields, the frame the reader picks the C runtime's (cb_runtime_frame_in) at every time, and the
 * kept rows' matrices and travel offsets the uniform file's at their cells. */
static void test_timed_rows_round_trip(void **state)
{
    (void)state;
    static const char *const variants[] = {"--precision half", "--precision u16 --layout qpos", "--precision float --layout mat4"};
    for (size_t v = 0; v < COUNT_OF(variants); ++v) {
        cbpal_file uni, f;
        cb_palette t, view, uview;
        cb_error e = {0};
        char err[256];
        write_timed_fox(variants[v], TMP "/timed.pal", &uni, &uview, &t);
        if (cbpal_open(TMP "/timed.pal", CBPAL_VERIFY_CHECKSUM, &f, err, sizeof err)) fail_msg("%s", err);
        assert_int_equal(uni.header.version, 5); /* Fox's travel offsets */
        assert_int_equal(f.header.version, 7);
        assert_true((f.header.flags & CBPAL_FLAG_TIMED_ROWS) && f.header.timed_table_offset >= CBPAL_HEADER_SIZE);
        assert_true(f.header.travel_table_offset != 0);
        assert_int_equal(f.texels_size, t.texel_bytes);
        assert_memory_equal(f.texels, t.texels, t.texel_bytes);
        assert_int_equal(cb_palette_view(&f, &view, &e), CB_OK);
        double worst = 0, worst_travel = 0, h = f.header.model_height;
        for (uint32_t c = 0; c < f.header.clip_count; ++c) {
            cbpal_clip clip, u;
            cbpal_get_clip(&f, c, &clip), cbpal_get_clip(&uni, c, &u);
            const cb_palette_clip *vc = &view.clips[c];
            assert_int_equal(!!(clip.flags & CBPAL_CLIP_TIMED), c != 0);
            assert_int_equal(vc->timed, c != 0);
            assert_int_equal(clip.cells, t.clips[c].cells);
            assert_int_equal(vc->cells, t.clips[c].cells);
            assert_int_equal(vc->map_rows, t.clips[c].map_rows);
            assert_true(vc->cell_rate == (float)t.clips[c].cell_rate);
            assert_int_equal(clip.frames, t.clips[c].frames);
            cb_instance in = cb_instance_of(vc);
            double step = 1 / (7.0 * (vc->timed ? vc->cell_rate : vc->fps));
            for (double time = -0.2; time < vc->duration + 0.3; time += step) {
                uint32_t a0, a1, b0, b1;
                double afr;
                float bfr;
                cb_runtime_frame_in(&view, f.texels, &in, time, &a0, &a1, &afr);
                assert_int_equal(cbpal_clip_frame(&f, c, time, &b0, &b1, &bfr), 0);
                assert_int_equal(a0, b0);
                assert_int_equal(a1, b1);
                assert_true(fabs(afr - bfr) < 1e-6);
            }
            uint32_t kept[512];
            uint32_t n = vc->timed ? timed_subset_cells(vc->cells, vc->loops, kept) : 0;
            for (uint32_t k = 0; k < n; ++k) { /* row k of a timed clip is the uniform row at its cell */
                double time = kept[k] / vc->cell_rate;
                float a[16], b[16], ta[3], tb[3];
                for (uint32_t j = 0; j < f.header.bone_count; ++j) {
                    assert_int_equal(cbpal_bone_matrix(&f, c, time, j, a), 0);
                    assert_int_equal(cbpal_bone_matrix(&uni, c, time, j, b), 0);
                    for (int i = 0; i < 16; ++i) worst = fmax(worst, fabs(a[i] - b[i]) * (i % 4 == 3 ? 1 : h));
                }
                assert_int_equal(cbpal_travel_offset(&f, c, time, ta), 0);
                assert_int_equal(cbpal_travel_offset(&uni, c, time, tb), 0);
                for (int i = 0; i < 3; ++i) worst_travel = fmax(worst_travel, fabs(ta[i] - tb[i]));
            }
            (void)u;
        }
        printf("  %s: timed rows against the uniform ones at their cells: matrices %.3g, travel %.3g (height %.3g)\n",
               variants[v], worst, worst_travel, h);
        assert_true(worst < 1e-4 * h && worst_travel < 1e-4 * h);
        /* Only a .pal holds timed rows. */
        cb_babylon_write_options bo = {0};
        const char *other[] = {TMP "/timed.exr", TMP "/timed.ktx2", TMP "/timed.babylon"};
        for (int i = 0; i < 3; ++i) {
            e = (cb_error){0};
            cb_status rc = i == 0   ? cb_exr_write(other[i], &t, NULL, 0, 0, 0, 0, &e)
                           : i == 1 ? cb_ktx2_write(other[i], &t, NULL, 0, 0, 0, false, &e)
                                    : cb_babylon_write(other[i], &t, NULL, 0, &bo, &e);
            assert_int_not_equal(rc, CB_OK);
            if (v != 1 || i == 2) assert_non_null(strstr(e.message, "timed rows need a .pal")); /* EXR, KTX2 refuse u16 first */
            assert_int_not_equal(access(other[i], F_OK), 0);
        }
        /* The writer refuses a timed clip a reader would refuse. */
        t.clips[1].map_rows += 1;
        e = (cb_error){0};
        assert_int_not_equal(cb_pal_write(TMP "/inconsistent.pal", &t, NULL, 0, &(cb_pal_write_options){0}, &e), CB_OK);
        assert_non_null(strstr(e.message, "timed rows are inconsistent"));
        assert_int_not_equal(access(TMP "/inconsistent.pal", F_OK), 0);
        cb_palette_view_free(&view), cb_palette_view_free(&uview);
        timed_subset_free(&t);
        cbpal_close(&f), cbpal_close(&uni);
    }
}

/* The checksum of a copy whose bytes were changed on purpose, so the reader's own checks speak. */
static void fix_checksum(unsigned char *d)
{
    uint64_t end = rd64(d + 152) + rd64(d + 160);
    wr64(d + CBPAL_CHECKSUM_OFFSET, 0);
    wr64(d + CBPAL_CHECKSUM_OFFSET, cbpal_xxh64(d, (size_t)end));
}

/* Timed rows' tables and maps, each fault refused with a one-line message naming the clip. */
static void test_timed_corruption_is_rejected(void **state)
{
    (void)state;
    cbpal_file uni, f;
    cb_palette t, uview;
    char err[256];
    write_timed_fox("--precision float --layout qpos", TMP "/timed.pal", &uni, &uview, &t);
    size_t size;
    unsigned char *good = read_all(TMP "/timed.pal", &size), *d = malloc(size);
    assert_null(reader_error(good, size, err, sizeof err));
    assert_int_equal(cbpal_open_memory(good, size, 0, &f, err, sizeof err), 0);
    uint64_t table = rd64(good + 208), clips = rd64(good + 120), payload = rd64(good + 152);
    cbpal_clip walk;
    cbpal_get_clip(&f, 1, &walk);
    uint32_t x, y;
    cbpal_texel_xy(&f.header, walk.first_row - walk.map_rows, 0, &x, &y);
    uint64_t map = payload + ((uint64_t)y * f.header.width + x) * 16 + 16 * 6; /* Walk's cell 6: rows kept at cells 5 and 8 */
    uint64_t walk_entry = table + 16, walk_flags = clips + CBPAL_CLIP_SIZE + 28;
    uint32_t flags = (uint32_t)good[walk_flags];
    struct { uint64_t at; uint32_t value; int width; const char *needle, *what; } cases[] = {
        {208, 0, 8, "timed clip table", "table offset 0"},
        {208, 100, 8, "timed clip table", "table in the header"},
        {208, (uint32_t)size - 8, 8, "timed clip table", "table past the end"},
        {8, 6, 4, "flag bit 6 (timed rows) in a version 6 file", "bit 6 in a version 6 file"},
        {walk_entry, 0, 4, "bad timed entry", "cells 0"},
        {walk_entry + 4, 0x7fc00000u, 4, "bad timed entry", "cell rate NaN"},
        {walk_entry + 4, 0xbf800000u, 4, "bad timed entry", "cell rate -1"},
        {walk_entry + 8, walk.map_rows + 1, 4, "bad timed entry", "map rows one too many"},
        {walk_entry + 12, 1, 4, "bad timed entry", "reserved word not 0"},
        {clips + CBPAL_CLIP_SIZE + 8, walk.map_rows - 1, 4, "bad timed entry", "map rows before row 0"},
        {walk_flags, flags & ~(uint32_t)CBPAL_CLIP_TIMED, 4, "clip flag bit 3", "timed entry, clip flag clear"},
        {clips + 28, (uint32_t)good[clips + 28] | CBPAL_CLIP_TIMED, 4, "clip flag bit 3", "clip flag set, entry 0"},
        {12, (uint32_t)rd64(good + 12) & ~(uint32_t)CBPAL_FLAG_TIMED_ROWS, 4, "without timed rows", "header flag clear"},
        {map, 0x447a0000u, 4, "its map's cell 6", "map row 1000"},
        {map, 0x3fc00000u, 4, "its map's cell 6", "map row 1.5"},
        {map + 4, 0xbf800000u, 4, "its map's cell 6", "map row -1"},
        {map + 8, 0x3fc00000u, 4, "its map's cell 6", "weight 1.5"},
        {map + 8, 0x7fc00000u, 4, "its map's cell 6", "weight NaN"},
        {map + 12, 0, 4, "its map's cell 6", "f1 below f0"},
    };
    for (size_t i = 0; i < COUNT_OF(cases); ++i) {
        memcpy(d, good, size);
        if (cases[i].width == 8) wr64(d + cases[i].at, cases[i].value);
        else wr32(d + cases[i].at, cases[i].value);
        fix_checksum(d);
        expect_rejected(d, size, cases[i].needle, cases[i].what);
        const char *msg = reader_error(d, size, err, sizeof err);
        assert_null(strchr(msg, '\n'));
        bool files = strstr(cases[i].needle, "timed clip table") || strstr(cases[i].needle, "version");
        if (!files && !strstr(msg, "Walk") && !strstr(msg, "Survey")) fail_msg("%s: '%s' names no clip", cases[i].what, msg);
        if (!files && !strstr(msg, "re-bake")) fail_msg("%s: '%s' says no fix", cases[i].what, msg);
    }
    /* Truncated inside the timed table: the table lies outside the file before anything is read. */
    for (uint64_t cut = table; cut < table + 3 * 16; cut += 7) expect_rejected(good, (size_t)cut, "outside the file", "truncated");
    timed_subset_free(&t);
    cb_palette_view_free(&uview);
    cbpal_close(&f), cbpal_close(&uni);
    free(good), free(d);
}

static void test_zstd_payload_reads_back_identical(void **state)
{
    (void)state;
    char fox[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    bake(fox, TMP "/plain.pal", "");
    bake(fox, TMP "/packed.pal", "--zstd");
    cbpal_file a, b;
    char err[256];
    assert_int_equal(cbpal_open(TMP "/plain.pal", CBPAL_VERIFY_CHECKSUM, &a, err, sizeof err), 0);
    assert_int_equal(cbpal_open(TMP "/packed.pal", CBPAL_VERIFY_CHECKSUM, &b, err, sizeof err), 0);
    assert_true(b.header.flags & CBPAL_FLAG_ZSTD);
    assert_true(b.header.payload_size < a.header.payload_size);
    assert_int_equal(a.texels_size, b.texels_size);
    assert_memory_equal(a.texels, b.texels, a.texels_size);
    printf("  Fox payload %llu bytes, zstd %llu bytes\n", (unsigned long long)a.header.payload_size,
           (unsigned long long)b.header.payload_size);
    cbpal_close(&a), cbpal_close(&b);
}

static void inspect_frame_matches_sample(const char *options)
{
    char fox[1024], cmd[4096], out[256];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    bake(fox, TMP "/f.pal", options);
    snprintf(cmd, sizeof cmd,
             "%s inspect %s/f.pal --clip Walk --frame 7 > %s/inspect.json && "
             "%s sample %s --fps 30 --clip Walk --frame 7 --json > %s/sample.json && python3 -c \"import json; "
             "a = json.load(open('%s/inspect.json'))['joints']; b = json.load(open('%s/sample.json'))['clips'][0]['samples'][0]['joints']; "
             "print(len(a), len(b), max(abs(x - y) for m, n in zip(a, b) for x, y in zip(m, n)))\"",
             crowdbake_exe(), TMP, TMP, crowdbake_exe(), fox, TMP, TMP, TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), 0);
    int na = 0, nb = 0;
    double worst = 1;
    assert_int_equal(sscanf(out, "%d %d %lf", &na, &nb, &worst), 3);
    assert_int_equal(na, 24);
    assert_int_equal(nb, 24);
    printf("  %s: worst %.3g\n", options, worst);
    assert_true(worst < 1e-4); /* float32 storage of matrices whose terms reach ~100 */
}

static void test_inspect_frame_matches_sample(void **state)
{
    (void)state;
    inspect_frame_matches_sample("--layout mat4 --precision float");
    inspect_frame_matches_sample("--bone-space local --precision float"); /* local rows: inspect composes them */
}

static void test_failed_bake_leaves_no_file_and_keeps_the_old_one(void **state)
{
    (void)state;
    char fox[1024], spider[1024], cmd[2048], out[1024];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    shared_path(spider, sizeof spider, "assets/spider-animated-luanti/gltf_spider_animated.gltf");
    bake(fox, TMP "/keep.pal", "");
    size_t n0, n1;
    unsigned char *before = read_all(TMP "/keep.pal", &n0);
    /* qpos chosen explicitly cannot hold the spider: the bake fails after loading. */
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/keep.pal --layout qpos 2>&1", crowdbake_exe(), spider, TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_INPUT);
    unsigned char *after = read_all(TMP "/keep.pal", &n1);
    assert_int_equal(n0, n1);
    assert_memory_equal(before, after, n0);
    free(before), free(after);
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/missing-dir/x.pal 2>&1", crowdbake_exe(), fox, TMP);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_IO);
    assert_non_null(strstr(out, "does not exist"));
    snprintf(cmd, sizeof cmd, "ls -a %s | grep -c '\\.tmp\\.' ", TMP);
    run_command(cmd, out, sizeof out);
    assert_int_equal(atoi(out), 0); /* no temporary left behind */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_byte_identical_bakes),
        cmocka_unit_test(test_exr_reads_back_bit_identical_and_opens_in_openexr_tools),
        cmocka_unit_test(test_u16_is_refused_for_exr),
        cmocka_unit_test(test_corruption_is_rejected),
        cmocka_unit_test(test_local_corruption_is_rejected),
        cmocka_unit_test(test_timed_rows_round_trip),
        cmocka_unit_test(test_timed_corruption_is_rejected),
        cmocka_unit_test(test_zstd_payload_reads_back_identical),
        cmocka_unit_test(test_inspect_frame_matches_sample),
        cmocka_unit_test(test_failed_bake_leaves_no_file_and_keeps_the_old_one),
    };
    return cmocka_run_group_tests_name("pal-file", tests, setup, NULL);
}
