/* bake_model.c - a program outside crowdbake that bakes a model through the installed public
 * API, as an engine's asset tool would: `bake_model MODEL OUT.pal`. tests/install/test_install.c
 * builds it against an installed tree with pkg-config and with CMake. */
#include <crowdbake/crowdbake.h>
#include <crowdbake_pal.h>
#include <stdio.h>
#include <string.h>

#if CROWDBAKE_API_VERSION_MAJOR != 3
#error "written for crowdbake's API 3"
#endif

int main(int argc, char **argv)
{
    if (argc != 3) return fprintf(stderr, "usage: bake_model MODEL OUT.pal\n"), 2;
    cb_error err = {0};
    cb_limits limits = cb_default_limits();
    cb_model *model = cb_gltf_load(argv[1], &limits, &err);
    if (!model) return fprintf(stderr, "bake_model: %s\n", err.message), 1;
    cb_bake_job job;
    cb_bake_job_init(&job); /* its size, the default settings and limits */
    job.model = model;
    job.skin = 0;
    job.limits = limits;
    job.threads = 2;
    cb_output_path out = {CB_FORMAT_PAL, argv[2]}; /* one file: a .pal */
    job.outputs = &out, job.output_count = 1;
    cb_bake_result result;
    if (cb_bake_job_run(&job, &result, &err) == CB_OK) {
        const cb_palette *p = &result.outputs[0].palette;
        printf("%s: %u rows, %u bones, %s/%s, input hash %016llx\n", result.outputs[0].path, p->rows, p->bone_count,
               cb_layout_name(p->layout), cb_precision_name(p->precision),
               (unsigned long long)result.outputs[0].input_hash);
    } else {
        fprintf(stderr, "bake_model: %s\n", err.message);
    }
    cb_bake_result_free(&result);
    cb_bake_job_free(&job);
    cb_model_free(model);
    /* and read it back with the runtime reader */
    cbpal_file f;
    char msg[256];
    if (!err.status && cbpal_open(argv[2], CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg) == 0) {
        printf("read back: %ux%u texels\n", f.header.width, f.header.height);
        cbpal_close(&f);
    }
    return err.status ? 1 : 0;
}
