/* name_words.h (internal) - what a clip's or state's name says, word by word: the loop decision
 * (clip.c) and the locomotion decision (src/bake/locomotion.c) both read names this way. */
#ifndef CB_INTERNAL_NAME_WORDS_H
#define CB_INTERNAL_NAME_WORDS_H

#include <stddef.h>

/* The first word of `text` that matches one of `stems`: its index in stems, the word lower-cased
 * into `word`; -1 when none. Words are split at anything not a letter and where a lower-case
 * letter meets an upper-case one ("Idle_HitReact" is idle, hit, react); a word matches a stem as
 * itself or with an ending (walks, walking, trotted, running). */
int cb_name_find_word(const char *text, const char *const *stems, size_t count, char *word, size_t size);

#endif
