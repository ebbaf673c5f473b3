/*
 * test_loader.h - what the loader test files share, defined in
 * test_loader.c.
 */
#ifndef TESTS_TEST_LOADERS_H
#define TESTS_TEST_LOADERS_H

#include "scene/scene.h"
#include "support.h"

typedef int (*parse_fn)(const char *, const char *, size_t, scene_builder *, accel_error *);

/* The parser a file name's extension selects: .obj, .ply, else OFF. */
parse_fn test_loader_parser(const char *name);

#endif
