/* animals.h - the sample animals as joints, clips and a pose function per animal (animals.c);
 * gen_samples.c turns them into GLB files. */
#ifndef GEN_ANIMALS_H
#define GEN_ANIMALS_H

#include <stdbool.h>

#define PI 3.14159265358979323846
#define MAX_JOINTS 1024
#define MAX_CLIPS 128
#define KEY_RATE 24.0 /* keys per second written for every animated channel */

typedef enum role {
    R_ROOT, R_SPINE, R_NECK, R_HEAD, R_JAW, R_EAR, R_TAIL, R_HIP, R_UPPER, R_LOWER, R_FOOT, R_TOE,
    R_FIN, R_WING_IN, R_WING_MID, R_WING_TIP, R_BEAK
} role;

typedef struct joint {
    char name[32];
    int parent;
    double pos[3];   /* local rest translation */
    double width;    /* thickness of the bone box ending at this joint */
    role role;
    int side;        /* -1 left, +1 right, 0 centre */
    int front;       /* 1 for front legs */
    int chain;       /* index along its chain */
} joint;

typedef struct animal animal;
typedef void (*pose_fn)(const animal *a, int clip, int j, double t, double euler[3], double trans[3]);

typedef struct clip {
    const char *name;
    double duration;
    int loops;
} clip;

struct animal {
    const char *name;
    joint joints[MAX_JOINTS];
    int joint_count;
    clip clips[MAX_CLIPS];
    int clip_count;
    pose_fn pose;
    double speed[MAX_CLIPS]; /* root travel along +Z, m/s */
};

/* The animals: each fills *a (a zeroed animal) with its joints, clips and pose. */
void build_quadruped(animal *a);
void build_fish(animal *a);
void build_bird(animal *a);
/* A benchmark creature: a spine with limbs, `joints` in all, `clips` clips of `seconds` each. */
void build_bench(animal *a, int joints, int clips, double seconds, double key_rate);
/* Removes the joints `drop` selects (a LOD of a rig); lod1_drops: ears, jaw, toes, tail tip. */
void drop_joints(animal *a, const char *name, bool (*drop)(const joint *j));
bool lod1_drops(const joint *j);

#endif
