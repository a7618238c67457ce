/* plant_report.c - what `--plant-feet` changed, per clip, in the bake's log and its --json
 * (crowdbake/plant_feet.h). */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "crowdbake/plant_feet.h"

static const char *plant_clip_name(const cb_bake_job *job, uint32_t i)
{
    return job->plan[i].name ? job->plan[i].name : job->model->animations[job->plan[i].animation].name;
}

void cli_plant_print(const cb_bake_job *job)
{
    const cb_plant_report *r = cb_bake_job_plant_report(job);
    if (!r) return;
    printf("plant feet (--plant-feet):\n");
    for (uint32_t i = 0; i < r->clip_count; ++i) printf("  %s: %s\n", plant_clip_name(job, i), r->clips[i].why);
}

void cli_plant_clip_json(cb_json *j, const cb_plant_clip *c)
{
    cb_json_bool(j, "planted", c->planted);
    cb_json_string(j, "why", c->why);
    cb_json_number(j, "ground_speed", c->speed);
    cb_json_int(j, "feet", c->feet);
    cb_json_number(j, "slide_before", c->slide_before);
    cb_json_number(j, "slide_worst_before", c->slide_worst_before);
    cb_json_number(j, "slide_after", c->planted ? c->slide_after : c->slide_before);
    cb_json_number(j, "slide_worst_after", c->planted ? c->slide_worst_after : c->slide_worst_before);
    cb_json_number(j, "max_rotation_deg", c->max_rotation_deg);
    cb_json_number(j, "max_shortfall", c->max_shortfall);
}

void cli_plant_json(cb_json *j, const cb_bake_job *job)
{
    const cb_plant_report *r = cb_bake_job_plant_report(job);
    if (!r) return;
    cb_json_array(j, "plant_feet");
    for (uint32_t i = 0; i < r->clip_count; ++i) {
        cb_json_object(j, NULL);
        cb_json_string(j, "clip", plant_clip_name(job, i));
        cli_plant_clip_json(j, &r->clips[i]);
        cb_json_end(j);
    }
    cb_json_end(j);
}
