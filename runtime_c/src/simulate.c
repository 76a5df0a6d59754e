/* The run loop: a run of the model linked into this program (fsm_system_model) or of a model
 * given as a struct (fsr_simulate_system), by an integrator picked from the table below by
 * method or name (integrator.h: rk4.c, dopri5.c, genalpha.c, newmark.c, radau5.c on a run of
 * ode.h; ali3p.c, genalpha3.c, rk4p.c on a run of constrained.h). It opens the run with the workspace
 * the integrator declares, writes the row at t = 0, calls begin, then step until the run is done
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

/* The table of integrators: NULL for a method not in it. */
static const fsr_integrator* integrator_of(fsr_method m)
{
    switch (m) {
    case FSR_RK4: return fsr_integrator_rk4();
    case FSR_GENALPHA: return fsr_integrator_genalpha();
    case FSR_NEWMARK: return fsr_integrator_newmark();
    case FSR_DOPRI5: return fsr_integrator_dopri5();
    case FSR_RADAU5: return fsr_integrator_radau5();
    case FSR_ALI3P: return fsr_integrator_ali3p();
    case FSR_GENALPHA3: return fsr_integrator_genalpha3();
    case FSR_RK4P: return fsr_integrator_rk4p();
    }
    return NULL;
}

const char* fsr_method_name(fsr_method m)
{
    const fsr_integrator* it = integrator_of(m);
    return it ? it->name : "?";
}

int fsr_method_by_name(const char* name, fsr_method* m)
{
    const fsr_integrator* it;
    for (int i = 0; (it = integrator_of((fsr_method)i)) != NULL; ++i)  /* methods are 0, 1, ... */
        if (!strcmp(it->name, name)) {
            *m = it->method;
            return 1;
        }
    return 0;
}

/* sim_open, refused for a method not in the table (it = NULL) */
static fsr_status open_ode(sim* s, const fsr_integrator* it, const fsr_options* o, fsr_result* r, long capacity)
{
    if (!it) {
        memset(s, 0, sizeof *s);
        memset(r, 0, sizeof *r);
        s->o = o;
        s->r = r;
        return fsr_fail(r, FSR_BAD_OPTIONS, "unknown method %d", (int)o->method);
    }
    return sim_open(s, it, o, r, capacity);
}

/* cs_open, refused for a method that is not a constrained integrator */
static fsr_status open_constrained(csim* s, const fsr_integrator* it, const fsm_system* m, const fsr_options* o,
                                   fsr_result* r, long capacity)
{
    if (!it || !it->cs_step) {
        memset(s, 0, sizeof *s);
        memset(r, 0, sizeof *r);
        return fsr_fail(r, FSR_BAD_OPTIONS, "a model given as a struct runs with ali3p, genalpha3 or rk4p "
                        "(got method %d)", (int)o->method);
    }
    return cs_open(s, it, m, o, r, capacity);
}

fsr_status fsr_simulate(const fsr_options* o, fsr_result* r)
{
    const fsr_integrator* it = integrator_of(o->method);
    if (it && it->cs_step) return fsr_simulate_system(fsm_system_model(), o, r);
    sim s;
    fsr_status st = open_ode(&s, it, o, r, 0);
    if (!st) st = sim_store(&s, 0.0, s.state, s.state + s.n, NULL);
    if (!st) st = it->begin(&s);
    while (!st && !s.done) st = it->step(&s);
    sim_close(&s);
    r->status = st;
    return st;
}

fsr_status fsr_simulate_system(const fsm_system* m, const fsr_options* o, fsr_result* r)
{
    const fsr_integrator* it = integrator_of(o->method);
    csim s;
    fsr_status st = open_constrained(&s, it, m, o, r, 0);
    if (!st) st = cs_start(&s);
    if (!st) st = it->cs_begin(&s);
    while (!st && s.k < s.nsteps) st = it->cs_step(&s);
    cs_close(&s);
    r->status = st;
    return st;
}

/* ------------------------------------------------------------ a run advanced by the caller */

struct fsr_stepper {
    const fsr_integrator* it;
    sim s;
    csim c;         /* instead of s for ali3p and genalpha3 (constrained.c) */
    int constrained;
    fsr_options o;  /* a copy; p and mp still point to the caller's arrays */
    fsr_result r;   /* status, message, counters; rows: the one row at the current time */
};

fsr_stepper* fsr_stepper_new(const fsr_options* o, const double* drive)
{
    fsr_stepper* p = calloc(1, sizeof *p);
    if (!p) return NULL;
    sim* s = &p->s;
    const fsr_integrator* it = p->it = integrator_of(o->method);
    p->o = *o;
    p->o.out_every = 1;  /* any grid point may be asked for */
    if (it && it->cs_step) {
        csim* c = &p->c;
        p->constrained = 1;
        fsr_status st = open_constrained(c, it, fsm_system_model(), &p->o, &p->r, 1);
        if (!st && drive)
            st = cs_fail(c, FSR_BAD_OPTIONS, "%s: no drive given step by step (the model's drive runs)",
                         it->name);
        if (!st) st = cs_start(c);
        if (!st) st = it->cs_begin(c);
        p->r.status = st;
        return p;
    }
    fsr_status st = open_ode(s, it, &p->o, &p->r, 1);
    if (!st && it->fixed_grid && !it->fixed_grid(o))
        st = sim_fail(s, FSR_BAD_OPTIONS, "%s: the stepper takes fixed steps of dt (dopri5 needs tol = 0, "
                      "radau5 no step other than dt)", it->name);
    if (!st && drive && it->stability_limited && it->stability_limited(o))
        st = sim_fail(s, FSR_BAD_OPTIONS, "%s: a drive given step by step needs an unconditionally stable "
                      "method (the stability limit of this one depends on the drive to come)", it->name);
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
    if (p->constrained) return refuse(p, "%s: retuning is not available yet", p->it->name);
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
