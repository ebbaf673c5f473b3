/*
 * memory.c - large allocations on transparent huge pages where the system
 * offers them (accel.h).
 */
#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

#include "accel.h"

#define LARGE_BLOCK ((size_t)4 << 20)
#define HUGE_PAGE ((size_t)2 << 20)

void *accel_alloc_large(size_t n, size_t size, size_t align)
{
    if (size && n > SIZE_MAX / size) return NULL;
    size_t bytes = n && size ? n * size : 1;
    if (align < sizeof(void *)) align = sizeof(void *);
    if (bytes >= LARGE_BLOCK && align < HUGE_PAGE) align = HUGE_PAGE;
    void *p = NULL;
    if (posix_memalign(&p, align, bytes) != 0) return NULL;
#ifdef MADV_HUGEPAGE
    /* A hint: where the kernel refuses (THP off), 4 KiB pages as before. */
    if (bytes >= LARGE_BLOCK) (void)madvise(p, bytes & ~(HUGE_PAGE - 1), MADV_HUGEPAGE);
#endif
    return p;
}
