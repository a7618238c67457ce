/* roster_babylon.c - a catalog type's .bvat.json (format "babylon", docs/babylon.md): the states it
 * lists, where each clip starts in it, and whether the file on disk is this bake's. */
#include "roster_files.h"

#include <stdlib.h>

#include "crowdbake/babylon.h"

uint32_t roster_babylon_from(const cb_roster_type *t, uint32_t clip)
{
    uint32_t from = 0;
    for (uint32_t c = 0; c < clip; ++c) from += cb_babylon_clip_rows(t->clips[c].frames, t->clips[c].loops);
    return from;
}

void roster_json_babylon_play(cb_json *j, const cb_roster_type *t, uint32_t clip)
{
    const cb_roster_clip *c = &t->clips[clip];
    uint32_t from = roster_babylon_from(t, clip);
    cb_json_object(j, "babylon");
    cb_json_int(j, "from", from);
    cb_json_int(j, "to", from + cb_babylon_clip_rows(c->frames, c->loops) - 1);
    cb_json_number(j, "fps", c->fps);
    cb_json_end(j);
}

cb_babylon_state *roster_babylon_states(const cb_catalog_animal *an, const cb_roster_type *t)
{
    cb_babylon_state *states = calloc(an->state_count ? an->state_count : 1, sizeof *states);
    for (uint32_t s = 0; states && s < an->state_count; ++s)
        states[s] = (cb_babylon_state){an->states[s].name, (uint32_t)t->state_clip[s]};
    return states;
}

bool roster_babylon_up_to_date(const cb_roster_type *t)
{
    cb_babylon_facts facts;
    cb_error e = {0};
    if (cb_babylon_read_facts(t->babylon_path, &facts, &e)) return false;
    return facts.input_hash == t->input_hash && facts.height == roster_babylon_from(t, t->clip_count);
}
