/*
 * stab_cert.h - exp_stability's certification (stab_cert.c): every
 * built-in stiff case with a million rays and more, every watertight
 * configuration of its group, against the exact reference.
 */
#ifndef EXP_STAB_CERT_H
#define EXP_STAB_CERT_H

#include "engine/group.h"

/* Rays per built-in case in the certification: a fixed count, never a time
 * limit (issue 52: what is certified must not move with the machine). */
#define STAB_CERT_RAYS 1000000
#define STAB_CERT_RAYS_QUICK 20000

typedef struct {
    uint64_t cases, bad, rays, min_n, leak_min, traces; /* cases, those with a fault, ... */
    uint64_t leaks, leak_rays, contact_leak_rays, contact_leaks;
    /* pairs (case, configuration) listed, certified on the case's rays, on
     * a fixed fewer (stab_cert.c: cert_fewer), not at all (with the reason) */
    uint64_t listed, full, fewer, none, fewer_min;
    int configs_min, configs_max; /* configurations listed per case */
    exp_text rows, notes;         /* the table's rows; the pairs on fewer rays or none */
} stab_cert;

/* Threads of the certification: --threads when given, else every core. */
int stab_cert_threads(const exp_ctx *x);
/* Certifies built-in case ci with the first m configurations of g (built
 * on the case's scene); tallies into c. */
void stab_cert_case(exp_ctx *x, stab_cert *c, int ci, const exp_group *g, int m);
void stab_cert_free(stab_cert *c);
/* A packet mode (traverse=packet): traced with the caller's order kept. */
int stab_cert_is_packet(const char *spec);

#endif
