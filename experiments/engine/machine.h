/*
 * machine.h - the machine a report was measured on, recorded in full:
 * CPU model, caches, clock, cores and threads per core (/proc/cpuinfo and
 * /sys/devices/system/cpu), logical CPUs and memory (sysconf), load
 * average (/proc/loadavg), kernel, virtualization, vector extensions.
 * Fields that cannot be read say "unknown" (or 0); nothing fails.
 */
#ifndef EXP_MACHINE_H
#define EXP_MACHINE_H

#include <stddef.h>

typedef struct {
    char cpu[160];        /* model name */
    double mhz;           /* "cpu MHz" of /proc/cpuinfo (the clock the kernel saw) */
    double mhz_max;       /* cpufreq's maximum, 0 when not exposed (e.g. a VM) */
    int logical;          /* online logical CPUs (sysconf) */
    int cores;            /* physical cores: distinct (physical id, core id) */
    int sockets;
    int threads_per_core; /* logical / cores: 2 with SMT (hyper-threading) */
    char caches[256];     /* "L1d 32K per core, ..., L3 32768K shared by 2 CPUs" */
    char vector[96];      /* the SIMD extensions the kernels may use */
    double mem_gib;
    int virtual_machine;  /* the "hypervisor" CPU flag */
    char kernel[256];     /* uname: sysname release machine */
} exp_machine;

void exp_machine_read(exp_machine *m);
/* The 1, 5 and 15 minute load averages; 0 and -1 entries when unreadable. */
int exp_loadavg(double load[3]);
/* Runnable threads other than the caller, averaged over samples of
 * /proc/loadavg's running count taken every 10 ms for about 200 ms: what
 * competes for the cores now. (The load average cannot say it: during a
 * report the previous experiment alone holds it at 1.) -1 if unknown. */
double exp_others_running(void);
/* The compiler that built this program ("gcc 12.2.0"). */
const char *exp_compiler(void);
/* One Markdown table (| item | value |) describing m. */
void exp_machine_markdown(const exp_machine *m, char *buf, size_t n);

#endif
