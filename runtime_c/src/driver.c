/* Command-line driver: integrate a generated model, write CSV, report a JSON summary.
 *
 *   flexsym_<variant> [--t-end T] [--dt H]
 *                     [--integrator NAME (of the registry, flexsym/integrators.h)]
 *                     [--step H] [--tol TOL] [--max-steps N] [--rho-inf R] [--newmark-gamma G]
 *                     [--newmark-beta B] [--newton modified|full] [--newton-tol TOL]
 *                     [--param NAME=VALUE]... [--out FILE.csv] [--out-every K]
 *                     [--repeat N] [--blowup F] [--penalty KAPPA] [--energy] [--info]
 *
 * dopri5 adapts its step to --tol (0: fixed steps --dt); its rows are at the output grid,
 * multiples of out_every * dt, from its dense output. radau5 steps by --step (default --dt)
 * and writes rows every --dt from its collocation polynomial. --energy appends columns T, V, h
 * (kinetic and potential energy, Jacobi integral) to every row. ali3p, genalpha3 and rk4p integrate
 * models with constraints (a column `violation` after the outputs when the model has any).
 *
 * stdout: one JSON line (status, steps, CPU time of the integration alone).
 * stderr: one line naming what went wrong. Exit: 0 ok, 2 usage or an assembly that cannot
 * close, 3 simulation stopped, 4 I/O.
 * The CSV is written to a temporary file and renamed, so an existing file is replaced
 * only by a complete one; after a divergence it holds the rows computed up to then.
 * Limits and defaults come from flexsym/limits.h (written from flexsym/model/options.py); flexsym
 * checks every option before starting the driver, so these checks are a last line of defence.
 * With FLEXSYM_PARENT_PID set (flexsym sets it), the driver ends when that process does
 * (Linux: PR_SET_PDEATHSIG), so a killed run leaves no orphan that writes later.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#ifdef __linux__
#include <signal.h>
#include <sys/prctl.h>
#endif

#include "flexsym/limits.h"
#include "flexsym/runtime.h"
#include "flexsym/system.h"

#define MAX_REPEAT FSR_MAX_REPEAT

/* The model this driver is built with: flexsym_add_model (flexsym_runtime.cmake) compiles it
 * with -DFSM_MODEL=<its accessor>, e.g. fsm_geometric_model (system.h). */
#ifndef FSM_MODEL
#error "compile with -DFSM_MODEL=<the model's accessor> (flexsym_runtime.cmake: flexsym_add_model)"
#endif
const fsm_system* FSM_MODEL(void);

static int usage(const char* msg, const char* arg)
{
    fprintf(stderr, "flexsym runtime: %s%s%s\n", msg, arg ? ": " : "", arg ? arg : "");
    return 2;
}

static int parse_double(const char* s, double* out)
{
    char* end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end != '\0' || !isfinite(v)) return 0;
    *out = v;
    return 1;
}

static int parse_int(const char* s, long* out)
{
    char* end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end != '\0') return 0;
    *out = v;
    return 1;
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void json_string(FILE* f, const char* s)
{
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"' || *s == '\\') fputc('\\', f);
        if ((unsigned char)*s < 0x20) { fputc(' ', f); continue; }
        fputc(*s, f);
    }
    fputc('"', f);
}

static void json_names(FILE* f, const char* key, const char* const* names, int n)
{
    fprintf(f, "\"%s\": [", key);
    for (int i = 0; i < n; ++i) {
        if (i) fputs(", ", f);
        json_string(f, names[i]);
    }
    fputs("]", f);
}

static void print_info(const fsm_system* m)
{
    printf("{\"variant\": ");
    json_string(stdout, m->name);
    printf(", \"fingerprint\": ");
    json_string(stdout, m->fingerprint);
    printf(", \"generator\": ");
    json_string(stdout, m->generator);
    printf(", \"nq\": %d, \"ny\": %d, \"mass_constant\": %d, ", m->nq, m->ny, m->mass_constant);
    json_names(stdout, "coordinates", m->coord_names, m->nq);
    printf(", ");
    json_names(stdout, "outputs", m->output_names, m->ny);
    printf(", ");
    json_names(stdout, "params", m->param_names, m->np);
    printf(", ");
    json_names(stdout, "maneuver_params", m->drive_param_names, m->nmp);
    printf("}\n");
}

static int set_param(const fsm_system* m, double* p, double* mp, const char* arg)
{
    const char* eq = strchr(arg, '=');
    if (!eq) return 0;
    size_t len = (size_t)(eq - arg);
    double v;
    if (!parse_double(eq + 1, &v)) return 0;
    for (int i = 0; i < m->np; ++i)
        if (strlen(m->param_names[i]) == len && !strncmp(arg, m->param_names[i], len)) { p[i] = v; return 1; }
    for (int i = 0; i < m->nmp; ++i)
        if (strlen(m->drive_param_names[i]) == len && !strncmp(arg, m->drive_param_names[i], len)) {
            mp[i] = v;
            return 1;
        }
    return 0;
}

static int write_csv(const char* path, const fsm_system* m, const fsr_result* r)
{
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid()) >= (int)sizeof tmp) {
        fprintf(stderr, "flexsym runtime: output path too long: %s\n", path);
        return 0;
    }
    FILE* f = fopen(tmp, "w");
    if (!f) {
        fprintf(stderr, "flexsym runtime: cannot write %s: %s\n", tmp, strerror(errno));
        return 0;
    }
    fputs("t", f);
    int violation = m->nc > 0;
    for (int i = 0; i < m->ny; ++i) fprintf(f, ",%s", m->output_names[i]);
    if (violation) fputs(",violation", f);
    for (int i = 0; i < m->nq; ++i) fprintf(f, ",%s", m->coord_names[i]);
    if (r->ncols > 1 + m->ny + violation + m->nq) fputs(",T,V,h", f);
    fputc('\n', f);
    for (int k = 0; k < r->nrows; ++k) {
        const double* row = r->rows + (size_t)k * (size_t)r->ncols;
        for (int j = 0; j < r->ncols; ++j) fprintf(f, j ? ",%.17g" : "%.17g", row[j]);
        fputc('\n', f);
    }
    int ok = !ferror(f);
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path) != 0) {
        fprintf(stderr, "flexsym runtime: cannot write %s: %s\n", path, strerror(errno));
        remove(tmp);
        return 0;
    }
    return 1;
}

static int cmp_double(const void* a, const void* b)
{
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

/* End with the parent: SIGTERM when it dies, and now if it died before we got here. */
static void die_with_parent(void)
{
#ifdef __linux__
    const char* pp = getenv("FLEXSYM_PARENT_PID");
    long want;
    if (!pp || !parse_int(pp, &want)) return;
    if (prctl(PR_SET_PDEATHSIG, SIGTERM) != 0) return;
    if ((long)getppid() != want) _exit(143);
#endif
}

int main(int argc, char** argv)
{
    die_with_parent();
    const fsm_system* m = FSM_MODEL();
    fsr_options o;
    fsr_default_options(&o);
    double p[64], mp[64];
    if (m->np > 64 || m->nmp > 64) return usage("model has too many parameters", NULL);
    memcpy(p, m->param_defaults, sizeof(double) * (size_t)m->np);
    memcpy(mp, m->drive_param_defaults, sizeof(double) * (size_t)m->nmp);
    o.p = p;
    o.mp = mp;
    const char* out = NULL;
    long repeat = 1, lv;

    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        const char* val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--info")) { print_info(m); return 0; }
        if (!strcmp(a, "--energy")) { o.energy = 1; continue; }
        if (!val) return usage("missing value after", a);
        ++i;
        if (!strcmp(a, "--t-end")) { if (!parse_double(val, &o.t_end)) return usage("bad --t-end", val); }
        else if (!strcmp(a, "--dt")) { if (!parse_double(val, &o.dt)) return usage("bad --dt", val); }
        else if (!strcmp(a, "--rho-inf")) { if (!parse_double(val, &o.rho_inf)) return usage("bad --rho-inf", val); }
        else if (!strcmp(a, "--newmark-gamma")) { if (!parse_double(val, &o.nm_gamma)) return usage("bad --newmark-gamma", val); }
        else if (!strcmp(a, "--newmark-beta")) { if (!parse_double(val, &o.nm_beta)) return usage("bad --newmark-beta", val); }
        else if (!strcmp(a, "--blowup")) { if (!parse_double(val, &o.blowup)) return usage("bad --blowup", val); }
        else if (!strcmp(a, "--penalty")) { if (!parse_double(val, &o.penalty)) return usage("bad --penalty", val); }
        else if (!strcmp(a, "--newton-tol")) { if (!parse_double(val, &o.newton_tol)) return usage("bad --newton-tol", val); }
        else if (!strcmp(a, "--step")) { if (!parse_double(val, &o.step)) return usage("bad --step", val); }
        else if (!strcmp(a, "--tol")) { if (!parse_double(val, &o.tol)) return usage("bad --tol", val); }
        else if (!strcmp(a, "--max-steps")) {
            if (!parse_int(val, &o.max_steps) || o.max_steps < 1) return usage("bad --max-steps", val);
        } else if (!strcmp(a, "--newton")) {
            if (!strcmp(val, "modified")) o.newton_full = 0;
            else if (!strcmp(val, "full")) o.newton_full = 1;
            else return usage("unknown --newton (modified, full)", val);
        }
        else if (!strcmp(a, "--out")) out = val;
        else if (!strcmp(a, "--out-every")) {
            if (!parse_int(val, &lv) || lv < 1 || lv > FSR_MAX_STEPS) return usage("bad --out-every (rows every K steps)", val);
            o.out_every = (int)lv;
        } else if (!strcmp(a, "--repeat")) {
            if (!parse_int(val, &repeat) || repeat < 1 || repeat > MAX_REPEAT) return usage("bad --repeat (runs, 1 to FSR_MAX_REPEAT of flexsym/limits.h)", val);
        } else if (!strcmp(a, "--integrator")) {
            if (!fsr_method_by_name(val, &o.method)) return usage("unknown --integrator (flexsym/integrators.h lists them)", val);
        } else if (!strcmp(a, "--param")) {
            if (!set_param(m, p, mp, val)) return usage("bad --param (NAME=VALUE with a known name)", val);
        } else return usage("unknown option", a);
    }

    fsr_result r;
    double times[MAX_REPEAT];
    /* Repeated runs time the integration alone; the first is a warm-up when repeating. */
    long runs = repeat > 1 ? repeat + 1 : 1;
    for (long k = 0; k < runs; ++k) {
        if (k) fsr_free(&r);
        double t0 = cpu_seconds();
        fsr_simulate(m, &o, &r);
        double t1 = cpu_seconds();
        if (repeat == 1 || k > 0) times[repeat == 1 ? 0 : k - 1] = t1 - t0;
        if (r.status != FSR_OK) { repeat = 1; times[0] = t1 - t0; break; }
    }
    if (r.status == FSR_BAD_OPTIONS || r.status == FSR_ASSEMBLY) {
        fsr_free(&r);
        return usage(r.message, NULL);
    }
    qsort(times, (size_t)repeat, sizeof(double), cmp_double);
    int io_ok = out ? write_csv(out, m, &r) : 1;

    printf("{\"status\": \"%s\", \"message\": ", r.status == FSR_OK ? "ok" : r.status == FSR_DIVERGED ? "diverged" : "failed");
    json_string(stdout, r.message);
    printf(", \"integrator\": \"%s\", \"dt\": %.17g, \"tol\": %.17g, \"t_end\": %.17g, \"t_stop\": %.17g, "
           "\"steps\": %ld, \"accepted_steps\": %ld, \"rejected_steps\": %ld, \"h_min\": %.9g, "
           "\"h_max\": %.9g, \"newton\": \"%s\", \"newton_iterations\": %ld, \"jacobian_evaluations\": %ld, "
           "\"force_evaluations\": %ld, \"omega_max\": %.9g, \"rows\": %d, \"repeat\": %ld, "
           "\"cpu_median\": %.9g, \"cpu_min\": %.9g, \"cpu_max\": %.9g}\n",
           fsr_method_name(o.method), o.dt, o.tol, o.t_end, r.t_stop, r.steps, r.steps, r.rejected_steps,
           r.h_min, r.h_max, o.newton_full ? "full" : "modified", r.newton_iterations,
           r.jacobian_evaluations, r.force_evaluations, r.omega_max, r.nrows, repeat,
           times[repeat / 2], times[0], times[repeat - 1]);
    if (r.status != FSR_OK)
        fprintf(stderr, "flexsym: %s; %d rows up to t = %.6g s %s\n", r.message, r.nrows, r.t_stop,
                out ? "kept in the output file" : "computed");
    fsr_free(&r);
    if (!io_ok) return 4;
    return r.status == FSR_OK ? 0 : 3;
}
