/*
 * machine.c - what the report records about the machine (see machine.h).
 */
#include <stdio.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>
#include <sys/utsname.h>
#include <unistd.h>

#include "accel.h"
#include "machine.h"

/* The value after "key<tabs>: " of a /proc/cpuinfo line, or NULL. */
static const char *cpuinfo_value(char *line, const char *key)
{
    size_t k = strlen(key);
    if (strncmp(line, key, k) != 0 || (line[k] != ' ' && line[k] != '\t' && line[k] != ':'))
        return NULL;
    char *colon = strchr(line, ':');
    if (!colon) return NULL;
    colon++;
    while (*colon == ' ') colon++;
    colon[strcspn(colon, "\n")] = 0;
    return colon;
}

static int read_line(const char *path, char *buf, size_t n)
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    int ok = fgets(buf, (int)n, f) != NULL;
    fclose(f);
    if (!ok) return -1;
    buf[strcspn(buf, "\n")] = 0;
    return 0;
}

/* CPUs in a sysfs list such as "0-1,4-5" (1 when empty). */
static int count_cpus(const char *s)
{
    int count = 0;
    while (*s) {
        char *end;
        long a = strtol(s, &end, 10), b = a;
        if (end == s) break;
        if (*end == '-') {
            s = end + 1;
            b = strtol(s, &end, 10);
        }
        count += (int)(b - a + 1);
        s = *end == ',' ? end + 1 : end;
    }
    return count > 0 ? count : 1;
}

/* The caches of cpu0 as sysfs lists them, with who shares each. */
static void read_caches(exp_machine *m)
{
    size_t len = 0;
    m->caches[0] = 0;
    for (int i = 0; i < 8; i++) {
        char path[128], level[16], type[32], size[32], shared[64];
        snprintf(path, sizeof path, "/sys/devices/system/cpu/cpu0/cache/index%d/level", i);
        if (read_line(path, level, sizeof level)) break;
        snprintf(path, sizeof path, "/sys/devices/system/cpu/cpu0/cache/index%d/type", i);
        if (read_line(path, type, sizeof type)) type[0] = 0;
        snprintf(path, sizeof path, "/sys/devices/system/cpu/cpu0/cache/index%d/size", i);
        if (read_line(path, size, sizeof size)) snprintf(size, sizeof size, "?");
        snprintf(path, sizeof path,
                 "/sys/devices/system/cpu/cpu0/cache/index%d/shared_cpu_list", i);
        if (read_line(path, shared, sizeof shared)) shared[0] = 0;
        const char *t = !strcmp(type, "Data") ? "d" : !strcmp(type, "Instruction") ? "i" : "";
        int sharers = count_cpus(shared);
        if (len < sizeof m->caches)
            len += (size_t)snprintf(m->caches + len, sizeof m->caches - len,
                                    "%sL%s%s %s %s", len ? ", " : "", level, t, size,
                                    sharers > 1 ? "shared" : "per core");
        if (sharers > 1 && len < sizeof m->caches)
            len += (size_t)snprintf(m->caches + len, sizeof m->caches - len, " by %d CPUs", sharers);
    }
    if (!m->caches[0]) snprintf(m->caches, sizeof m->caches, "unknown");
}

static void read_cpuinfo(exp_machine *m)
{
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f) return;
    char line[4096];
    int phys = 0, core = 0, pairs[1024][2], npairs = 0, max_phys = -1;
    while (fgets(line, sizeof line, f)) {
        const char *v;
        if ((v = cpuinfo_value(line, "model name")) && !m->cpu[0])
            snprintf(m->cpu, sizeof m->cpu, "%s", v);
        else if ((v = cpuinfo_value(line, "cpu MHz")) && m->mhz == 0)
            m->mhz = atof(v);
        else if ((v = cpuinfo_value(line, "physical id")))
            phys = atoi(v);
        else if ((v = cpuinfo_value(line, "core id"))) {
            core = atoi(v);
            int seen = 0;
            for (int i = 0; i < npairs; i++) seen |= pairs[i][0] == phys && pairs[i][1] == core;
            if (!seen && npairs < 1024) pairs[npairs][0] = phys, pairs[npairs][1] = core, npairs++;
            if (phys > max_phys) max_phys = phys;
        } else if ((v = cpuinfo_value(line, "flags")) && !m->vector[0]) {
            static const char *const ext[] = {"sse4_2", "avx", "avx2", "fma", "avx512f", "avx512vl"};
            size_t len = 0;
            char padded[4100];
            snprintf(padded, sizeof padded, " %s ", v);
            m->virtual_machine = strstr(padded, " hypervisor ") != NULL;
            for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++) {
                char word[32];
                snprintf(word, sizeof word, " %s ", ext[i]);
                if (strstr(padded, word) && len < sizeof m->vector)
                    len += (size_t)snprintf(m->vector + len, sizeof m->vector - len, "%s%s",
                                            len ? " " : "", ext[i]);
            }
        }
    }
    fclose(f);
    if (npairs) m->cores = npairs, m->sockets = max_phys + 1;
}

void exp_machine_read(exp_machine *m)
{
    memset(m, 0, sizeof *m);
    read_cpuinfo(m);
    if (!m->cpu[0]) snprintf(m->cpu, sizeof m->cpu, "unknown");
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    m->logical = n > 0 ? (int)n : 1;
    if (m->cores <= 0) m->cores = m->logical, m->sockets = 1;
    m->threads_per_core = m->cores > 0 ? m->logical / m->cores : 1;
    if (m->threads_per_core < 1) m->threads_per_core = 1;
    char buf[64];
    if (read_line("/sys/devices/system/cpu/cpu0/cpufreq/cpuinfo_max_freq", buf, sizeof buf) == 0)
        m->mhz_max = atof(buf) / 1000.0;
    read_caches(m);
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0) m->mem_gib = (double)pages * (double)page / (1024.0 * 1024 * 1024);
    struct utsname u;
    if (uname(&u) == 0)
        snprintf(m->kernel, sizeof m->kernel, "%s %s %s", u.sysname, u.release, u.machine);
    else
        snprintf(m->kernel, sizeof m->kernel, "unknown");
    if (!m->vector[0]) snprintf(m->vector, sizeof m->vector, "none detected");
}

int exp_loadavg(double load[3])
{
    load[0] = load[1] = load[2] = 0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f) return -1;
    int ok = fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) == 3;
    fclose(f);
    return ok ? 0 : -1;
}

double exp_others_running(void)
{
    double sum = 0;
    int n = 0;
    for (int i = 0; i < 20; i++) {
        FILE *f = fopen("/proc/loadavg", "r");
        if (!f) return -1;
        double l1, l5, l15;
        int running, total;
        if (fscanf(f, "%lf %lf %lf %d/%d", &l1, &l5, &l15, &running, &total) == 5)
            sum += running - 1, n++; /* the reader itself is running */
        fclose(f);
        struct timespec ts = {0, 10000000};
        nanosleep(&ts, NULL);
    }
    return n ? sum / n : -1;
}

const char *exp_compiler(void)
{
#if defined(__clang__)
    return "clang " __clang_version__;
#elif defined(__GNUC__)
    return "gcc " __VERSION__;
#else
    return "unknown compiler";
#endif
}

/* The ISA the wide kernels use in this run (accel_isa_name: picked at
 * run time from cpuid, GRIDBVH_ISA=avx2 forces the baseline), the
 * baseline every other unit was compiled for, and the CPU's own. */
static void kernel_isa(const exp_machine *m, char *buf, size_t n)
{
#if defined(__AVX512F__)
    const char *base = "AVX-512";
#elif defined(__AVX2__)
    const char *base = "AVX2";
#else
    const char *base = "SSE2";
#endif
    char padded[128];
    snprintf(padded, sizeof padded, " %s ", m->vector);
    snprintf(buf, n, "wide BVH kernels %s (picked at run time), other code %s; the CPU has %s",
             accel_isa_name(), base, strstr(padded, " avx512f ") ? "AVX-512" : "AVX2 at most");
}

void exp_machine_markdown(const exp_machine *m, char *buf, size_t n)
{
    char isa[192];
    kernel_isa(m, isa, sizeof isa);
    char mhz[64];
    if (m->mhz_max > 0)
        snprintf(mhz, sizeof mhz, "%.0f MHz (maximum %.0f MHz)", m->mhz, m->mhz_max);
    else
        snprintf(mhz, sizeof mhz, "%.0f MHz (no frequency scaling exposed)", m->mhz);
    snprintf(buf, n,
             "| machine | %s |\n"
             "| clock | %s |\n"
             "| cores | %d logical CPUs: %d core%s on %d socket%s, %d thread%s per core%s |\n"
             "| caches (cpu0) | %s |\n"
             "| vector extensions | %s |\n"
             "| kernel ISA | %s |\n"
             "| memory | %.1f GiB |\n"
             "| kernel | %s%s |\n",
             m->cpu, mhz, m->logical, m->cores, m->cores == 1 ? "" : "s", m->sockets,
             m->sockets == 1 ? "" : "s", m->threads_per_core, m->threads_per_core == 1 ? "" : "s",
             m->threads_per_core == 1 ? " (no SMT siblings visible)" : " (SMT)", m->caches,
             m->vector, isa, m->mem_gib, m->kernel,
             m->virtual_machine ? ", a virtual machine (the hypervisor CPU flag is set): the "
                                  "topology is the one it presents"
                                : "");
}
