/* speed_task.c - the speed reference decided beside the palette (speed_task.h). */
#include "speed_task.h"

#include <string.h>

#include "../core/foot_cache.h"

static int measure_main(void *survey)
{
    speed_survey_measure(survey);
    return 0;
}

void speed_task_start(cb_bake_job *job, struct foot_cache *feet, struct clip_memo *memo, speed_task *task)
{
    memset(task, 0, sizeof *task);
    if (job->speed_reference >= 0) return;
    uint32_t threads = job->threads ? job->threads : 1;
    task->survey = speed_survey_begin(feet, memo, job->model, job->skin, job->plan, job->plan_count, threads);
    task->started = threads > 1 && task->survey && thrd_create(&task->thread, measure_main, task->survey) == thrd_success;
    if (!task->started) speed_task_finish(job, task); /* one thread (or none to start): decided here, as before */
}

void speed_task_finish(cb_bake_job *job, speed_task *task)
{
    if (task->started) thrd_join(task->thread, NULL);
    else if (task->survey) speed_survey_measure(task->survey);
    if (job->speed_reference < 0)
        job->speed_reference = speed_survey_end(task->survey, job->speed_reference_from, sizeof job->speed_reference_from);
    task->survey = NULL, task->started = false;
}
