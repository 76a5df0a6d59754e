/* The run loop: a run of a model given as a struct (system.h) by an integrator picked from the
 * registry (flexsym/integrators.h) by method or name: a run of ode.h for rk4.c, dopri5.c,
 * genalpha.c, newmark.c, radau5.c, of constrained.h for those with FSR_CAP_CONSTRAINED (ali3p.c,
 * genalpha3.c, rk4p.c). It opens the run with the workspace the integrator's descriptor declares
 * (integrator.h), writes the row at t = 0, calls begin, then step until the run is done
 * (fsr_simulate) or up to the time the caller asks for (fsr_stepper); so both give the same
 * rows bit for bit. It knows no integrator's internals.
 */
#include "flexsym/runtime.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "constrained.h"
#include "integrator.h"
#include "ode.h"

/* The registry: one entry per line of flexsym/integrators.h. */
typedef struct {
    const char* name;
    fsr_method method;
    unsigned caps;
    const fsr_integrator* (*descriptor)(void);
} registered;

static const registered REGISTRY[] = {
#define FSR_INTEGRATOR(name, NAME, code, caps) {#name, FSR_##NAME, caps, fsr_integrator_##name},
#include "flexsym/integrators.h"
#undef FSR_INTEGRATOR
};
enum { NREGISTERED = sizeof REGISTRY / sizeof REGISTRY[0] };

/* NULL for a method not in the registry */
static const registered* registered_of(fsr_method m)
{
    for (int i = 0; i < NREGISTERED; ++i)
        if (REGISTRY[i].method == m) return &REGISTRY[i];
    return NULL;
}

const char* fsr_method_name(fsr_method m)
{
    const registered* e = registered_of(m);
    return e ? e->name : "?";
}

int fsr_method_by_name(const char* name, fsr_method* m)
{
    for (int i = 0; i < NREGISTERED; ++i)
        if (!strcmp(REGISTRY[i].name, name)) {
            *m = REGISTRY[i].method;
            return 1;
        }
    return 0;
}

/* sim_open, refused for a method not in the registry (e = NULL) */
static fsr_status open_ode(sim* s, const registered* e, const fsm_system* m, const fsr_options* o, fsr_result* r,
                           long capacity)
{
    if (!e) {
        memset(s, 0, sizeof *s);
        memset(r, 0, sizeof *r);
        s->o = o;
        s->r = r;
        return fsr_fail(r, FSR_BAD_OPTIONS, "unknown method %d", (int)o->method);
    }
    return sim_open(s, e->descriptor(), m, o, r, capacity);
}

fsr_status fsr_simulate(const fsm_system* m, const fsr_options* o, fsr_result* r)
{
    const registered* e = registered_of(o->method);
    fsr_status st;
    if (e && (e->caps & FSR_CAP_CONSTRAINED)) {
        const fsr_integrator* it = e->descriptor();
        csim c;
        st = cs_open(&c, it, m, o, r, 0);
        if (!st) st = cs_start(&c);
        if (!st) st = it->cs_begin(&c);
        while (!st && c.k < c.nsteps) st = it->cs_step(&c);
        cs_close(&c);
    } else {
        sim s;
        st = open_ode(&s, e, m, o, r, 0);
        if (!st) {
            const fsr_integrator* it = e->descriptor();
            st = sim_store(&s, 0.0, s.state, s.state + s.n, NULL);
            if (!st) st = it->begin(&s);
            while (!st && !s.done) st = it->step(&s);
        }
        sim_close(&s);
    }
    r->status = st;
    return st;
}

/* ------------------------------------------------------------ a run advanced by the caller */

struct fsr_stepper {
    const fsr_integrator* it;
    sim s;
    csim c;         /* instead of s for a constrained integrator (constrained.c) */
    int constrained;
    fsr_options o;  /* a copy; p and mp still point to the caller's arrays */
    fsr_result r;   /* status, message, counters; rows: the one row at the current time */
};

fsr_stepper* fsr_stepper_new(const fsm_system* m, const fsr_options* o, const double* drive)
{
    fsr_stepper* p = calloc(1, sizeof *p);
    if (!p) return NULL;
    sim* s = &p->s;
    const registered* e = registered_of(o->method);
    const fsr_integrator* it = p->it = e ? e->descriptor() : NULL;
    p->o = *o;
    p->o.out_every = 1;  /* any grid point may be asked for */
    if (e && (e->caps & FSR_CAP_CONSTRAINED)) {
        csim* c = &p->c;
        p->constrained = 1;
        fsr_status st = cs_open(c, it, m, &p->o, &p->r, 1);
        if (!st && drive)
            st = cs_fail(c, FSR_BAD_OPTIONS, "%s: no drive given step by step (the model's drive runs)",
                         e->name);
        if (!st) st = cs_start(c);
        if (!st) st = it->cs_begin(c);
        p->r.status = st;
        return p;
    }
    fsr_status st = open_ode(s, e, m, &p->o, &p->r, 1);
    if (!st && !(e->caps & FSR_CAP_FIXED_GRID) && !it->fixed_grid(o))
        st = sim_fail(s, FSR_BAD_OPTIONS, "%s: the stepper takes fixed steps of dt (dopri5 needs tol = 0, "
                      "radau5 no step other than dt)", e->name);
    /* the registry says which methods take a drive at all; Newmark's stability limit depends on
     * its options */
    if (!st && drive && (!(e->caps & FSR_CAP_DRIVE_INPUT) || (it->stability_limited && it->stability_limited(o))))
        st = sim_fail(s, FSR_BAD_OPTIONS, "%s: a drive given step by step needs an unconditionally stable "
                      "method (the stability limit of this one depends on the drive to come)", e->name);
    if (!st && drive && s->nd != 4)
        st = sim_fail(s, FSR_BAD_OPTIONS, "a drive given step by step needs a model with one guided joint "
                      "(this one has %d drive values)", s->nd);
    if (!st && drive) {
        s->drive_held = 1;
        s->hold_t = 0.0;
        s->hold_theta = 0.0;
        s->hold[0] = drive[0];
        s->hold[1] = drive[1];
    }
    if (!st) st = sim_store(s, 0.0, s->state, s->state + s->n, NULL);
    if (!st) st = it->begin(s);
    p->r.status = st;
    return p;
}

const fsr_result* fsr_stepper_result(const fsr_stepper* p)
{
    return &p->r;
}

double fsr_stepper_time(const fsr_stepper* p)
{
    return p->constrained ? cs_time(&p->c, p->c.k) : sim_time(&p->s, p->s.k);
}

/* A refused request leaves the run as it was: the message says why, the status stays. */
static fsr_status refuse(fsr_stepper* p, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(p->r.message, sizeof p->r.message, fmt, ap);
    va_end(ap);
    return FSR_BAD_OPTIONS;
}

fsr_status fsr_stepper_advance(fsr_stepper* p, double t)
{
    sim* s = &p->s;
    csim* c = &p->c;
    fsr_result* r = &p->r;
    const fsr_options* o = &p->o;
    if (r->status) return r->status;
    long now = p->constrained ? c->k : s->k, nsteps = p->constrained ? c->nsteps : s->nsteps;
    double dt = o->dt, x = t / dt;
    if (!(x > (double)now && x < (double)nsteps + 0.5))
        return refuse(p, "t = %.17g s is not after the current time %.17g s and up to t_end = %.17g s", t,
                      fsr_stepper_time(p), o->t_end);
    double eps = 1e-9 * (dt > fabs(t) ? dt : fabs(t));
    long k = fabs(t - o->t_end) <= eps ? nsteps : (long)floor(x + 0.5);
    if (k > nsteps) k = nsteps;
    double tk = fsr_step_time(o, nsteps, k);
    if (k <= now || !(fabs(tk - t) <= eps))
        return refuse(p, "t = %.17g s is not on the step grid (multiples of dt = %.17g s, and t_end)", t, dt);
    r->nrows = 0;
    fsr_status st = FSR_OK;
    if (p->constrained) {
        c->next_row = k;
        while (!st && c->k < k) st = p->it->cs_step(c);
    } else {
        s->next_row = k;
        while (!st && s->k < k) st = p->it->step(s);
    }
    r->nrows = 1;  /* the row at t_k; after a failure, the last row stored */
    r->status = st;
    return st;
}

fsr_status fsr_stepper_set_drive(fsr_stepper* p, double theta_d, double theta_dd)
{
    sim* s = &p->s;
    if (!s->drive_held) return refuse(p, "this run takes its drive from the manoeuvre");
    if (!isfinite(theta_d) || !isfinite(theta_dd)) return refuse(p, "drive values must be finite");
    double now = sim_time(s, s->k), tau = now - s->hold_t;
    s->hold_theta += tau * (s->hold[0] + 0.5 * s->hold[1] * tau);  /* theta continues */
    s->hold_t = now;
    s->hold[0] = theta_d;
    s->hold[1] = theta_dd;
    return FSR_OK;
}

fsr_status fsr_stepper_retune(fsr_stepper* p)
{
    sim* s = &p->s;
    fsr_result* r = &p->r;
    if (r->status) return r->status;
    if (p->constrained) return refuse(p, "%s: retuning is not available yet", fsr_method_name(p->o.method));
    fsr_status st = sim_retune(s, p->it);
    r->status = st;
    return st;
}

void fsr_stepper_free(fsr_stepper* p)
{
    if (!p) return;
    if (p->constrained) cs_close(&p->c);
    else sim_close(&p->s);
    fsr_free(&p->r);
    free(p);
}

void fsr_free(fsr_result* r)
{
    free(r->rows);
    r->rows = NULL;
    r->nrows = 0;
}
