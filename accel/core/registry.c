/*
 * registry.c - the one place that names every accelerator kind.
 *
 * Adding a backend: write its folder (see grid/ or bvh/), declare its kind
 * below and add one line to accel_kinds[]. Tools, tests and experiments
 * iterate over this table; nothing else names a backend.
 */
#include <string.h>

#include "accel.h"

extern const accel_kind accel_kind_brute;
extern const accel_kind accel_kind_bvh;
extern const accel_kind accel_kind_grid;
extern const accel_kind accel_kind_irregular_grid;
extern const accel_kind accel_kind_nested_grid;
extern const accel_kind accel_kind_instanced;
#ifdef GRIDBVH_LAB
extern const accel_kind accel_kind_student; /* lab/student.c, in `make lab` builds only */
extern const accel_kind accel_kind_student_grid; /* lab/student_grid.c, likewise */
#endif

const accel_kind *const accel_kinds[] = {
    &accel_kind_brute,
    &accel_kind_bvh,
    &accel_kind_grid,
    &accel_kind_irregular_grid,
    &accel_kind_nested_grid,
    &accel_kind_instanced,
#ifdef GRIDBVH_LAB
    &accel_kind_student,
    &accel_kind_student_grid,
#endif
};
const size_t accel_kind_count = sizeof accel_kinds / sizeof accel_kinds[0];

const accel_kind *accel_find_kind(const char *name)
{
    for (size_t i = 0; i < accel_kind_count; i++)
        if (!strcmp(accel_kinds[i]->name, name)) return accel_kinds[i];
    return NULL;
}

