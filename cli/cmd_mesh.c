/* cmd_mesh.c - `crowdbake mesh MODEL -o OUT.glb`: the mesh a palette runtime draws, ready to
 * upload: joints as palette bones, fewer influences, quantized attributes, batches. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "catalog/catalog_toml.h"
#include "crowdbake/gltf_mesh_write.h"
#include "crowdbake/mesh.h"
#include "cli.h"
#include "mesh_skin.h"

const char cmd_mesh_usage[] =
    "usage: crowdbake mesh MODEL -o OUT.glb [--palette-model MAIN] [--max-influences 1|2|4] [--quantize] [--batch K]\n"
    "                      [--max-quantization-error MM_PER_M] [--fps N] [--skin NAME|INDEX] [--vertex-id-uv N]\n"
    "                      [--skin-texture FILE.cbskin] [--json] [-q] [-v]\n"
    "       crowdbake mesh CATALOG.toml --type NAME [--lod N] -o OUT.glb [options]\n\n"
    "Writes the skinned mesh as a palette runtime draws it, a .glb validated by the Khronos validator:\n"
    "  JOINTS_0 are palette bones: the mesh's joints remapped by name to the skin the palette is baked\n"
    "  from (--palette-model, or a catalog type's model for its LODs: --lod N, 0 the model itself).\n"
    "  --max-influences N  keep each vertex's N largest weights, renormalized (default 4; a catalog's\n"
    "                      lod_max_influences gives one per LOD)\n"
    "  --quantize          KHR_mesh_quantization: normals as normalized i8, weights as u8 (summing to 255)\n"
    "                      where that adds at most --max-quantization-error mm/m (default 0.1) to the error\n"
    "                      of float weights, else u16; texcoords as u16 when within 0..1; positions stay\n"
    "                      float (the palette's matrices expect bind-space positions, which a\n"
    "                      dequantization transform would change)\n"
    "  --batch K           K copies in one mesh with a per-copy attribute _INSTANCE_ID (SCALAR FLOAT, 0..K-1),\n"
    "                      for runtimes without instancing (CB_BATCH in runtimes/glsl/crowdbake_palette.glsl)\n"
    "  --vertex-id-uv N    TEXCOORD_N = (vertex id, 0): each vertex's index over all parts, for engines whose\n"
    "                      instanced meshes carry no skin and may reorder vertices on import (Unreal: UV channel\n"
    "                      N, with full-precision UVs); channels below N the mesh lacks are written as zeros\n"
    "  --skin-texture FILE.cbskin  the joints and weights by that vertex id, as a texture (runtimes/unreal/README.md)\n"
    "  --fps N             frame rate the error is measured at (default 30)\n"
    "Prints the extra vertex error against the model's own 4-influence skinning over every frame of every\n"
    "clip (mm per metre of height, worst vertex and clip), and the bytes of the vertex and index buffers.\n";

typedef struct mesh_args {
    const char *input, *output, *palette_model, *type, *lod, *influences, *batch, *fps, *skin, *max_quant;
    const char *vertex_id_uv, *skin_texture;
    uint32_t vertex_id_set;
    bool quantize, json;
    cli_output out; /* -q: no summary line */
} mesh_args;

/* Resolves a catalog's --type/--lod into model paths and the LOD's influence setting. */
static int from_catalog(mesh_args *a, cb_catalog *cat, unsigned *influences, cb_error *err)
{
    if (cb_catalog_load(a->input, cat, err)) return cli_report(err);
    if (a->palette_model) return cli_usage_error("mesh", "--palette-model is for a model; a catalog type's LODs use its model");
    if (!a->type) return cli_usage_error("mesh", "%s: give --type NAME (an [animal.NAME] of the catalog)", a->input);
    const cb_catalog_animal *an = NULL;
    for (uint32_t i = 0; i < cat->animal_count; ++i)
        if (strcmp(cat->animals[i].name, a->type) == 0) an = &cat->animals[i];
    if (!an) return cli_usage_error("mesh", "%s: has no animal type '%s'", a->input, a->type);
    unsigned lod = 0;
    if (a->lod && (!cli_parse_u32(a->lod, &lod) || lod > an->lod_count))
        return cli_usage_error("mesh", "%s: [animal.%s] has %u LODs; --lod is 0 (the model) to %u", a->input, a->type,
                               an->lod_count, an->lod_count);
    a->palette_model = an->model;
    a->input = lod ? an->lods[lod - 1] : an->model;
    if (!a->influences && lod && an->lod_max_influences) *influences = an->lod_max_influences[lod - 1];
    return 0;
}

static void print_result(const mesh_args *a, const cb_mesh *m, const cb_mesh_error *e, const cb_model *pm)
{
    uint64_t vb, ib, verts = 0;
    cb_mesh_bytes(m, &vb, &ib);
    for (uint32_t i = 0; i < m->part_count; ++i) verts += m->parts[i].vertex_count;
    const char *clip = e->worst_animation >= 0 ? pm->animations[e->worst_animation].name : "rest pose";
    if (a->json) {
        cb_json j;
        cb_json_init(&j, stdout);
        cb_json_object(&j, NULL);
        cb_json_string(&j, "output", a->output);
        cb_json_string(&j, "model", a->input);
        cb_json_string(&j, "palette_model", a->palette_model ? a->palette_model : a->input);
        cb_json_int(&j, "vertices", (long long)verts);
        cb_json_int(&j, "primitives", m->part_count);
        cb_json_int(&j, "max_influences", m->max_influences);
        cb_json_bool(&j, "quantized", m->quantized);
        cb_json_int(&j, "batch", m->batch);
        if (m->batch > 1) cb_json_string(&j, "instance_id_attribute", CB_INSTANCE_ID_ATTRIBUTE);
        if (a->vertex_id_uv) cb_json_int(&j, "vertex_id_texcoord", a->vertex_id_set);
        if (a->skin_texture) cb_json_string(&j, "skin_texture", a->skin_texture);
        cb_json_int(&j, "vertex_buffer_bytes", (long long)vb);
        cb_json_int(&j, "index_buffer_bytes", (long long)ib);
        cb_json_number(&j, "error", e->max);
        cb_json_number(&j, "error_mm_per_m", e->max_mm_per_m);
        cb_json_number(&j, "model_height", e->height);
        cb_json_int(&j, "worst_vertex", (long long)e->worst_vertex);
        cb_json_string(&j, "worst_clip", clip);
        cb_json_number(&j, "worst_time", e->worst_time);
        cb_json_int(&j, "frames_measured", e->frames);
        if (m->quantized) cb_json_int(&j, "weight_bits", m->weight_scale == 255 ? 8 : 16);
        if (m->quantized) cb_json_number(&j, "normal_error_degrees", m->normal_error_deg);
        if (m->quantized) cb_json_number(&j, "texcoord_error", m->texcoord_error);
        cb_json_end(&j);
        return;
    }
    if (a->out.quiet) return;
    printf("%s: %llu vertices%s, %u influence%s%s, vertex buffers %.1f KiB + indices %.1f KiB; extra error vs 4 "
           "influences %.3f mm/m (vertex %llu, '%s' at %.3f s, %u frames at the palette model's clips)",
           a->output, (unsigned long long)verts, m->batch > 1 ? " (batch of copies with _INSTANCE_ID)" : "", m->max_influences,
           m->max_influences == 1 ? "" : "s", !m->quantized ? "" : m->weight_scale == 255 ? ", quantized (u8 weights)" : ", quantized (u16 weights)", vb / 1024.0, ib / 1024.0, e->max_mm_per_m,
           (unsigned long long)e->worst_vertex, clip, e->worst_time, e->frames);
    bool normals = false;
    for (uint32_t i = 0; i < m->part_count; ++i) normals |= m->parts[i].normals_i8 != NULL;
    if (normals) printf(", normals within %.2f deg", m->normal_error_deg);
    if (a->vertex_id_uv) printf("; vertex ids in TEXCOORD_%u", a->vertex_id_set);
    if (a->skin_texture) printf("; joints and weights by vertex id in %s", a->skin_texture);
    printf("\n");
}

/* Writes the .glb, with --vertex-id-uv N's channel unless the model's own texture coordinates are there. */
static cb_status write_glb(const mesh_args *a, const cb_mesh *mesh, const cb_model *pm, int32_t ps, const cb_mesh_error *e,
                           cb_error *err)
{
    if (!a->vertex_id_uv) return cb_gltf_mesh_write(a->output, mesh, pm, ps, e, err);
    for (uint32_t i = 0; i < mesh->part_count && a->vertex_id_set == 0; ++i)
        if (mesh->parts[i].texcoords)
            return cb_fail(err, CB_ERR_INPUT, "%s: TEXCOORD_0 holds the model's texture coordinates; put the vertex id in "
                           "another channel (--vertex-id-uv 1)", a->input);
    return cb_gltf_mesh_write_vertex_ids(a->output, mesh, pm, ps, e, a->vertex_id_set, err);
}

/* Loads the mesh's model and the palette's, the remap between their skins, and does the job. */
static int run(mesh_args *a, unsigned influences, unsigned batch, double fps, double max_quant, const cb_limits *limits)
{
    cb_error err = {0};
    cb_model *pm = NULL, *mm = NULL;
    uint32_t *remap = NULL;
    cb_sampler *s = NULL;
    cb_mesh mesh = {0};
    int ps = -1, ms = -1;
    bool same = !a->palette_model || strcmp(a->palette_model, a->input) == 0;
    if (!(pm = cli_load_model(&a->out, same ? a->input : a->palette_model, limits, &err)) || (ps = cli_pick_skin(pm, a->skin, &err)) < 0)
        goto done;
    mm = same ? pm : cli_load_model(&a->out, a->input, limits, &err);
    if (!mm || (ms = same ? ps : cli_pick_skin(mm, NULL, &err)) < 0) goto done;
    if (!same) {
        remap = calloc(mm->skins[ms].joint_count, sizeof *remap);
        if (!remap) cb_fail(&err, CB_ERR_INTERNAL, "out of memory");
        if (!remap || cb_lod_remap(pm, ps, mm, ms, remap, &err)) goto done;
    }
    cb_mesh_options o = {influences, a->quantize, false, batch, remap, pm->skins[ps].joint_count};
    cb_mesh_error e;
    double t0 = cli_seconds();
    if (!(s = cb_sampler_create(pm, ps, &err)) || cb_mesh_build_measured(s, mm, ms, &o, fps, max_quant, &mesh, &e, &err) ||
        write_glb(a, &mesh, pm, ps, &e, &err) ||
        (a->skin_texture && cli_write_skin_texture(a->skin_texture, &mesh, &err)))
        goto done;
    cli_verbose(&a->out, "built, measured and wrote %s in %.3f s", a->output, cli_seconds() - t0);
    print_result(a, &mesh, &e, pm);
done:
    cb_sampler_free(s);
    cb_mesh_free(&mesh);
    free(remap);
    if (mm != pm) cb_model_free(mm);
    cb_model_free(pm);
    return err.status ? cli_report(&err) : 0;
}

int cmd_mesh(int argc, char **argv)
{
    cb_limits limits;
    if (cli_take_limits(&argc, argv, &limits)) return CLI_EXIT_USAGE;
    mesh_args a = {0};
    if (cli_take_output(&argc, argv, &a.out)) return CLI_EXIT_USAGE;
    bool help;
    const cli_option options[] = {
        {"-o", "OUT.glb", &a.output, NULL},          {"--output", "OUT.glb", &a.output, NULL},
        {"--palette-model", "MAIN", &a.palette_model, NULL}, {"--type", "NAME", &a.type, NULL},
        {"--lod", "N", &a.lod, NULL},                {"--max-influences", "N", &a.influences, NULL},
        {"--quantize", NULL, NULL, &a.quantize},     {"--batch", "K", &a.batch, NULL},
        {"--fps", "N", &a.fps, NULL},                {"--skin", "NAME|INDEX", &a.skin, NULL},
        {"--json", NULL, NULL, &a.json},             {"--max-quantization-error", "MM_PER_M", &a.max_quant, NULL},
        {"--vertex-id-uv", "N", &a.vertex_id_uv, NULL}, {"--skin-texture", "FILE.cbskin", &a.skin_texture, NULL}};
    int rc = cli_parse(argc, argv, options, sizeof options / sizeof options[0], &a.input, 1, 1, &help);
    if (help) return fputs(cmd_mesh_usage, stdout), fputs(cli_output_usage, stdout), fputs(cli_limits_usage, stdout), 0;
    if (rc) return rc;
    if (!a.output) return cli_usage_error("mesh", "-o OUT.glb is required");
    unsigned influences = 4, batch = 1;
    double fps = 30, max_quant = 0.1;
    if (a.influences && (!cli_parse_u32(a.influences, &influences) || (influences != 1 && influences != 2 && influences != 4)))
        return cli_usage_error("mesh", "--max-influences is 1, 2 or 4");
    if (a.batch && (!cli_parse_u32(a.batch, &batch) || batch == 0 || batch > 65536))
        return cli_usage_error("mesh", "--batch wants a count of copies from 1 to 65536");
    if (a.fps && (!cli_parse_double(a.fps, &fps) || !cb_fps_valid(fps)))
        return cli_usage_error("mesh", "--fps wants a frame rate above 0 (up to 1000)");
    if (a.max_quant && (!cli_parse_double(a.max_quant, &max_quant) || !(max_quant >= 0)))
        return cli_usage_error("mesh", "--max-quantization-error wants mm per metre of height (0 or more)");
    if (a.max_quant && !a.quantize) return cli_usage_error("mesh", "--max-quantization-error goes with --quantize");
    if (a.vertex_id_uv && (!cli_parse_u32(a.vertex_id_uv, &a.vertex_id_set) || a.vertex_id_set > 7))
        return cli_usage_error("mesh", "--vertex-id-uv wants a texture coordinate set from 0 to 7 (Unreal has 8 UV channels)");
    if (a.skin_texture && !a.vertex_id_uv)
        return cli_usage_error("mesh", "--skin-texture is read by vertex id: give --vertex-id-uv N too");
    const char *ext = strrchr(a.output, '.');
    if (!ext || strcmp(ext, ".glb") != 0) return cli_usage_error("mesh", "%s: the mesh is written as a .glb; name it OUT.glb", a.output);
    cb_catalog cat = {0};
    bool catalog = cli_file_kind_of(a.input) == CLI_FILE_UNKNOWN && strstr(a.input, ".toml");
    if (!catalog && (a.type || a.lod))
        return cli_usage_error("mesh", "--type and --lod pick a catalog's type and LOD; %s is not a catalog", a.input);
    if (catalog && (rc = from_catalog(&a, &cat, &influences, &(cb_error){0}))) {
        cb_catalog_free(&cat);
        return rc;
    }
    rc = run(&a, influences, batch, fps, max_quant, &limits);
    if (catalog) cb_catalog_free(&cat);
    return rc;
}
