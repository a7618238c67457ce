/* speed_task.h - the speed reference nobody gave (locomotion.h), decided for a bake run with its
 * strides measured beside the palette. Every clip is analyzed first (speed_survey_begin, on the
 * caller's thread: it reads and fills the run's clip memo), then the clips' strides are measured
 * on a thread of their own (speed_survey_measure, itself on the job's threads) while the palette
 * bakes: they share nothing (the strides read the model and write the run's foot cache, which the
 * palette never touches; the palette reads the clip memo, which the strides never touch), so the
 * serial steps of each (the palette's framing and skin facts, the feet found in the rest pose)
 * run while the other keeps the cores busy. The speed reference is read back (speed_survey_end)
 * before the per-row travel, which asks the foot cache for the same strides. Same numbers, bit for
 * bit, as deciding it first: each stride depends on its clip alone, not on when it is measured. */
#ifndef CB_SPEED_TASK_H
#define CB_SPEED_TASK_H

#include <stdbool.h>
#include <threads.h>

#include "crowdbake/bake.h"

struct foot_cache;
struct clip_memo;
struct speed_survey;

typedef struct speed_task {
    struct speed_survey *survey; /* NULL: nothing to read back */
    thrd_t thread;
    bool started;                /* the strides are being measured on `thread` */
} speed_task;

/* Starts deciding job->speed_reference unless one was given; with one thread, decides it here. */
void speed_task_start(cb_bake_job *job, struct foot_cache *feet, struct clip_memo *memo, speed_task *task);

/* Waits for the strides and sets job->speed_reference and job->speed_reference_from; again, nothing. */
void speed_task_finish(cb_bake_job *job, speed_task *task);

#endif
