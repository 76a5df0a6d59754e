/* Test runner for the hand-written models: fsr_simulate_system on the linked fixture's
 * fsm_system_model(), without simulate.c or the generated-model globals.
 *   run_<fixture> [--integrator ali3p|genalpha3] [--dt H] [--t-end T] [--out-every K]
 *                 [--penalty KAPPA] [--rho-inf R] [--newton modified|full] [--newton-tol TOL]
 *                 [--energy] [--param NAME=VALUE]... --out FILE.csv
 * stdout: one JSON line; stderr: the message. Exit 0 ok, 2 refused (options, assembly), 3 failed. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flexsym/runtime.h"
#include "flexsym/system.h"

static int set_param(const fsm_system* m, double* p, double* mp, const char* arg)
{
    const char* eq = strchr(arg, '=');
    if (!eq) return 0;
    size_t len = (size_t)(eq - arg);
    double v = atof(eq + 1);
    for (int i = 0; i < m->np; ++i)
        if (strlen(m->param_names[i]) == len && !strncmp(arg, m->param_names[i], len)) { p[i] = v; return 1; }
    for (int i = 0; i < m->nmp; ++i)
        if (strlen(m->drive_param_names[i]) == len && !strncmp(arg, m->drive_param_names[i], len)) { mp[i] = v; return 1; }
    return 0;
}

int main(int argc, char** argv)
{
    const fsm_system* m = fsm_system_model();
    double p[32], mp[32];
    memcpy(p, m->param_defaults, sizeof(double) * (size_t)m->np);
    memcpy(mp, m->drive_param_defaults, sizeof(double) * (size_t)m->nmp);
    fsr_options o;
    memset(&o, 0, sizeof o);  /* fsr_default_options lives in simulate.c: the same values */
    o.method = FSR_ALI3P;
    o.t_end = 1.0;
    o.dt = 1e-3;
    o.out_every = 1;
    o.rho_inf = 0.9;
    o.newton_tol = 1e-12;
    o.newton_max = 25;
    o.penalty = 1e7;
    o.p = p;
    o.mp = mp;
    const char* out = NULL;
    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        if (!strcmp(a, "--energy")) { o.energy = 1; continue; }
        if (i + 1 >= argc) { fprintf(stderr, "missing value after %s\n", a); return 2; }
        const char* v = argv[++i];
        if (!strcmp(a, "--integrator")) {
            if (!strcmp(v, "ali3p")) o.method = FSR_ALI3P;
            else if (!strcmp(v, "genalpha3")) o.method = FSR_GENALPHA3;
            else { fprintf(stderr, "unknown --integrator %s\n", v); return 2; }
        } else if (!strcmp(a, "--dt")) o.dt = atof(v);
        else if (!strcmp(a, "--t-end")) o.t_end = atof(v);
        else if (!strcmp(a, "--out-every")) o.out_every = atoi(v);
        else if (!strcmp(a, "--penalty")) o.penalty = atof(v);
        else if (!strcmp(a, "--rho-inf")) o.rho_inf = atof(v);
        else if (!strcmp(a, "--newton-tol")) o.newton_tol = atof(v);
        else if (!strcmp(a, "--newton")) o.newton_full = !strcmp(v, "full");
        else if (!strcmp(a, "--param")) {
            if (!set_param(m, p, mp, v)) { fprintf(stderr, "bad --param %s\n", v); return 2; }
        } else if (!strcmp(a, "--out")) out = v;
        else { fprintf(stderr, "unknown option %s\n", a); return 2; }
    }
    fsr_result r;
    fsr_status st = fsr_simulate_system(m, &o, &r);
    if (out && r.nrows > 0) {
        FILE* f = fopen(out, "w");
        if (!f) { fprintf(stderr, "cannot write %s\n", out); return 4; }
        fputs("t", f);
        for (int i = 0; i < m->ny; ++i) fprintf(f, ",%s", m->output_names[i]);
        if (m->nc) fputs(",violation", f);
        for (int i = 0; i < m->nq; ++i) fprintf(f, ",%s", m->coord_names[i]);
        if (o.energy) fputs(",T,V,h", f);
        fputc('\n', f);
        for (int k = 0; k < r.nrows; ++k)
            for (int j = 0; j < r.ncols; ++j)
                fprintf(f, j + 1 < r.ncols ? "%.17g," : "%.17g\n", r.rows[(size_t)k * (size_t)r.ncols + (size_t)j]);
        fclose(f);
    }
    printf("{\"status\": %d, \"steps\": %ld, \"newton_iterations\": %ld, \"jacobian_evaluations\": %ld, "
           "\"rows\": %d}\n", (int)st, r.steps, r.newton_iterations, r.jacobian_evaluations, r.nrows);
    if (st) fprintf(stderr, "%s\n", r.message);
    free(r.rows);
    return st == FSR_OK ? 0 : (st == FSR_BAD_OPTIONS || st == FSR_ASSEMBLY) ? 2 : 3;
}
