/* plant_report.c - what `--plant-feet` changed, per clip, in the bake's log and its --json
 * (crowdbake/plant_feet.h). */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "crowdbake/plant_feet.h"
#include "roster/roster.h"

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

void cli_plant_json(cb_json *j, const cb_bake_job *job)
{
    const cb_plant_report *r = cb_bake_job_plant_report(job);
    if (!r) return;
    cb_json_array(j, "plant_feet");
    for (uint32_t i = 0; i < r->clip_count; ++i) {
        cb_json_object(j, NULL);
        cb_json_string(j, "clip", plant_clip_name(job, i));
        cb_roster_json_plant(j, &r->clips[i]);
        cb_json_end(j);
    }
    cb_json_end(j);
}
