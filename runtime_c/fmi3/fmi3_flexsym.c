/* FMI 3.0 Co-Simulation interface of a generated flexsym model (see README, "FMI 3.0 export").
 *
 * One instance is one run of the C runtime advanced by fsr_stepper (runtime.h): fmi3DoStep
 * integrates with the exported integrator and its fixed step dt up to the next communication
 * point, which must lie on that step grid; the outputs are the row flexsym run would write
 * there. flexsym_fmu_config.h, written by `flexsym export-fmu` (flexsym/sim/fmu.py), holds the
 * instantiation token, the run options, the start values and the value references.
 * Unsupported functions log one line and return fmi3Error, as do invalid calls and values.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3.h"
#include "flexsym/limits.h"
#include "flexsym/runtime.h"
#include "flexsym/system.h"
#include "flexsym_fmu_config.h"

/* The model, named by the configuration (its generated folder's accessor, system.h) */
const fsm_system* FSU_MODEL(void);

/* GetFloat64 reads outputs (with a system's violation column, FSU_NY counts it) and
 * coordinates as one block of the row */
typedef char fsu_vr_layout_check[FSU_VR_Q == FSU_VR_Y + FSU_NY ? 1 : -1];


typedef enum { INSTANTIATED, INITIALIZATION, STEP, TERMINATED, FAILED } fsu_state;

typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    char name[128];
    fsu_state state;
    const fsm_system* m;  /* the model (system.h), which every runtime call is given */
    double p[FSU_NP > 0 ? FSU_NP : 1], mp[FSU_NMP > 0 ? FSU_NMP : 1], drive[2];
    double t_end;      /* the defined stopTime, else horizon() */
    int stop_defined;
    fsr_options o;
    fsr_stepper* run;
    int stale;   /* a value changed in initialization mode: start the run again */
    int retune;  /* a parameter changed in step mode: fsr_stepper_retune before the next step */
} fsu;

static const char* STATE_NAMES[] = {"instantiated", "initialization mode", "step mode", "terminated",
                                    "failed"};

static fmi3Status say(const fsu* c, fmi3Status st, const char* fmt, ...)
{
    if (!c || !c->log) return st;
    char msg[640];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c->env, st, st == fmi3Discard ? "logStatusDiscard" : "logStatusError", msg);
    return st;
}

static fmi3Status unsupported(fmi3Instance instance, const char* what)
{
    return say(instance, fmi3Error, "%s is not supported by this FMU (flexsym Co-Simulation, "
               "fixed internal step, no event mode, no FMU state)", what);
}

/* Without a stop time (stopTimeDefined = false, FMI 3.0: none) the run goes on until the importer
 * stops calling fmi3DoStep, up to the runtime's limit of FSR_MAX_STEPS steps of dt (1e5 s at
 * 1 ms): the grid point of that many steps, rounded down so that the runtime counts exactly
 * FSR_MAX_STEPS steps. The stepper keeps one row, so a long run costs no memory. */
static double horizon(void)
{
    const double dt = FSU_DT, n = (double)FSR_MAX_STEPS;
    double t = n * dt;
    while (t / dt > n || ceil(t / dt - 1e-9) > n) t = nextafter(t, 0.0);
    return t;
}

static void defaults(fsu* c)
{
    static const double p0[] = FSU_P_START, mp0[] = FSU_MP_START;
    memcpy(c->p, p0, sizeof(double) * FSU_NP);
    if (FSU_NMP) memcpy(c->mp, mp0, sizeof(double) * FSU_NMP);
    c->drive[0] = c->drive[1] = 0.0;
    fsr_default_options(&c->o);
    c->o.method = FSU_METHOD;
    c->o.dt = FSU_DT;
    c->o.step = FSU_STEP;
    c->o.tol = FSU_TOL;
    FSU_TUNE(c->o); /* the integrator settings given at export (rho_inf, Newmark, Newton, ...) */
    c->o.out_every = 1;
    c->o.p = c->p;
    c->o.mp = c->mp;
    c->t_end = horizon();
    c->stop_defined = 0;
    fsr_stepper_free(c->run);
    c->run = NULL;
    c->stale = c->retune = 0;
}

/* ---------------------------------------------------------------- life cycle */

const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    (void)loggingOn, (void)nCategories, (void)categories;  /* only errors are logged, always */
    return instance ? fmi3OK : fmi3Error;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
    const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables,
    fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
    fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath, (void)visible, (void)loggingOn, (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables, (void)intermediateUpdate;
    fsu probe = {0};
    probe.env = instanceEnvironment;
    probe.log = logMessage;
    snprintf(probe.name, sizeof probe.name, "%s", instanceName ? instanceName : "?");
    const fsm_system* m = FSU_MODEL();
    if (m->np != FSU_NP || m->nmp != FSU_NMP || m->ny + (m->nc > 0) != FSU_NY || m->nq != FSU_NQ) {
        say(&probe, fmi3Error, "%s: the binary does not match its configuration", probe.name);
        return NULL;
    }
    if (!instantiationToken || strcmp(instantiationToken, FSU_TOKEN) != 0) {
        say(&probe, fmi3Error, "%s: instantiationToken '%s' is not this model's (%s)", probe.name,
            instantiationToken ? instantiationToken : "(null)", FSU_TOKEN);
        return NULL;
    }
    if (eventModeUsed || nRequiredIntermediateVariables) {
        say(&probe, fmi3Error, "%s: this FMU has no event mode and no intermediate update", probe.name);
        return NULL;
    }
    fsu* c = calloc(1, sizeof *c);
    if (!c) {
        say(&probe, fmi3Error, "%s: out of memory", probe.name);
        return NULL;
    }
    *c = probe;
    c->m = m;
    defaults(c);
    c->state = INSTANTIATED;
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    fsu probe = {0};
    probe.env = instanceEnvironment;
    probe.log = logMessage;
    say(&probe, fmi3Error, "Model Exchange is not supported by this FMU (Co-Simulation only)");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    fsu probe = {0};
    probe.env = instanceEnvironment;
    probe.log = logMessage;
    say(&probe, fmi3Error, "Scheduled Execution is not supported by this FMU (Co-Simulation only)");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    fsu* c = instance;
    if (!c) return;
    fsr_stepper_free(c->run);
    free(c);
}

static fmi3Status in_state(fsu* c, const char* fn, int allowed)
{
    if (!c) return fmi3Error;
    if (allowed & (1 << c->state)) return fmi3OK;
    return say(c, fmi3Error, "%s: %s is not allowed in %s", c->name, fn, STATE_NAMES[c->state]);
}
#define IN(s) (1 << (s))

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    fsu* c = instance;
    (void)toleranceDefined, (void)tolerance;  /* fixed steps: the step, not a tolerance, sets the error */
    if (in_state(c, "fmi3EnterInitializationMode", IN(INSTANTIATED))) return fmi3Error;
    if (startTime != 0.0)
        return say(c, fmi3Error, "%s: startTime = %g s; this FMU starts at t = 0 (its manoeuvre and "
                   "its step grid do)", c->name, startTime);
    if (stopTimeDefined && !(stopTime > 0.0 && isfinite(stopTime)))
        return say(c, fmi3Error, "%s: stopTime = %g s must be > 0", c->name, stopTime);
    if (stopTimeDefined && !(stopTime <= horizon()))
        return say(c, fmi3Error, "%s: stopTime = %g s is %.3g steps of dt = %g s, more than this FMU's "
                   "limit of %ld steps (stopTime <= %.17g s; without a stop time it runs up to there)",
                   c->name, stopTime, stopTime / FSU_DT, FSU_DT, FSR_MAX_STEPS, horizon());
    c->stop_defined = stopTimeDefined ? 1 : 0;
    c->t_end = stopTimeDefined ? stopTime : horizon();
    c->o.t_end = c->t_end;
    c->state = INITIALIZATION;
    c->stale = 1;
    return fmi3OK;
}

/* (Re)start the run at t = 0 with the current parameters and inputs. */
static fmi3Status start_run(fsu* c)
{
    fsr_stepper_free(c->run);
    c->run = fsr_stepper_new(c->m, &c->o, FSU_DRIVE_INPUT ? c->drive : NULL);
    if (!c->run) return say(c, fmi3Error, "%s: out of memory", c->name);
    c->stale = c->retune = 0;
    const fsr_result* r = fsr_stepper_result(c->run);
    if (r->status != FSR_OK) return say(c, fmi3Error, "%s: %s", c->name, r->message);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    fsu* c = instance;
    if (in_state(c, "fmi3ExitInitializationMode", IN(INITIALIZATION))) return fmi3Error;
    if ((c->stale || !c->run) && start_run(c) != fmi3OK) {
        c->state = FAILED;
        return fmi3Error;
    }
    c->state = STEP;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return in_state(instance, "fmi3EnterStepMode", IN(STEP));
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    fsu* c = instance;
    if (in_state(c, "fmi3Terminate", IN(STEP) | IN(FAILED))) return fmi3Error;
    c->state = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    fsu* c = instance;
    if (!c) return fmi3Error;
    defaults(c);
    c->state = INSTANTIATED;
    return fmi3OK;
}

/* ------------------------------------------------------------------ variables */

typedef enum { V_TIME, V_P, V_MP, V_IN, V_Y, V_Q, V_NONE } vkind;

static vkind kind_of(fmi3ValueReference vr, int* i)
{
    const long v = (long)vr;
    if (v == FSU_VR_TIME) return V_TIME;
    if (v >= FSU_VR_P && v < FSU_VR_P + FSU_NP) return *i = (int)(v - FSU_VR_P), V_P;
    if (!FSU_DRIVE_INPUT && v >= FSU_VR_MP && v < FSU_VR_MP + FSU_NMP) return *i = (int)(v - FSU_VR_MP), V_MP;
    if (FSU_DRIVE_INPUT && v >= FSU_VR_IN && v < FSU_VR_IN + 2) return *i = (int)(v - FSU_VR_IN), V_IN;
    if (v >= FSU_VR_Y && v < FSU_VR_Y + FSU_NY) return *i = (int)(v - FSU_VR_Y), V_Y;
    if (v >= FSU_VR_Q && v < FSU_VR_Q + FSU_NQ) return *i = (int)(v - FSU_VR_Q), V_Q;
    return V_NONE;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    fsu* c = instance;
    if (in_state(c, "fmi3GetFloat64", IN(INSTANTIATED) | IN(INITIALIZATION) | IN(STEP) | IN(TERMINATED) | IN(FAILED)))
        return fmi3Error;
    if (nValues != nValueReferences || (nValueReferences && (!valueReferences || !values)))
        return say(c, fmi3Error, "%s: fmi3GetFloat64: %zu values for %zu value references (all variables "
                   "are scalars)", c->name, nValues, nValueReferences);
    /* outputs and coordinates: row[1 + vr - FSU_VR_Y] (t, outputs, coordinates; FSU_VR_Q follows
     * the outputs), read after every step, so first */
    const double* row = c->run && !c->stale ? fsr_stepper_result(c->run)->rows : NULL;
    for (size_t j = 0; j < nValueReferences; ++j) {
        long y = (long)valueReferences[j] - FSU_VR_Y;
        if (row && y >= 0 && y < FSU_NY + FSU_NQ) {
            values[j] = row[1 + y];
            continue;
        }
        int i = 0;
        vkind k = kind_of(valueReferences[j], &i);
        if (k == V_NONE)
            return say(c, fmi3Error, "%s: fmi3GetFloat64: no Float64 variable has value reference %u", c->name,
                       (unsigned)valueReferences[j]);
        if (k == V_Y || k == V_Q || k == V_TIME) {
            if (c->state == INSTANTIATED && k != V_TIME)
                return say(c, fmi3Error, "%s: outputs are known from initialization mode on", c->name);
            if (c->state == INITIALIZATION && (c->stale || !c->run) && start_run(c) != fmi3OK) return fmi3Error;
            row = c->run ? fsr_stepper_result(c->run)->rows : NULL;
        }
        switch (k) {
        case V_TIME: values[j] = row ? row[0] : 0.0; break;
        case V_P: values[j] = c->p[i]; break;
        case V_MP: values[j] = c->mp[i]; break;
        case V_IN: values[j] = c->drive[i]; break;
        case V_Y: values[j] = row[1 + i]; break;
        case V_Q: values[j] = row[1 + FSU_NY + i]; break;
        case V_NONE: break;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    fsu* c = instance;
    if (in_state(c, "fmi3SetFloat64", IN(INSTANTIATED) | IN(INITIALIZATION) | IN(STEP))) return fmi3Error;
    if (nValues != nValueReferences || (nValueReferences && (!valueReferences || !values)))
        return say(c, fmi3Error, "%s: fmi3SetFloat64: %zu values for %zu value references (all variables "
                   "are scalars)", c->name, nValues, nValueReferences);
    for (size_t j = 0; j < nValueReferences; ++j) {  /* check all before changing any */
        int i = 0;
        double v = values[j];
        switch (kind_of(valueReferences[j], &i)) {
        case V_P:
            if (!(v > 0.0) || !isfinite(v))
                return say(c, fmi3Error, "%s: parameter %s must be a positive number (got %g)", c->name,
                           c->m->param_names[i], v);
            break;
        case V_MP:
            if (!isfinite(v))
                return say(c, fmi3Error, "%s: parameter %s must be finite (got %g)", c->name,
                           c->m->drive_param_names[i], v);
            break;
        case V_IN:
            if (!isfinite(v)) return say(c, fmi3Error, "%s: input %s must be finite (got %g)", c->name,
                                         i ? "theta_ddot" : "theta_dot", v);
            if (c->state == INSTANTIATED)
                return say(c, fmi3Error, "%s: inputs are set from initialization mode on", c->name);
            break;
        default:
            return say(c, fmi3Error, "%s: fmi3SetFloat64: value reference %u is not a parameter or an input",
                       c->name, (unsigned)valueReferences[j]);
        }
    }
    int params = 0, inputs = 0;
    for (size_t j = 0; j < nValueReferences; ++j) {
        int i = 0;
        vkind k = kind_of(valueReferences[j], &i);
        if (k == V_P) c->p[i] = values[j], params = 1;
        else if (k == V_MP) c->mp[i] = values[j], params = 1;
        else c->drive[i] = values[j], inputs = 1;
    }
    if (c->state == INITIALIZATION) c->stale = 1;
    if (c->state == STEP && params) c->retune = 1;
    if (c->state == STEP && inputs && fsr_stepper_set_drive(c->run, c->drive[0], c->drive[1]) != FSR_OK)
        return say(c, fmi3Error, "%s: %s", c->name, fsr_stepper_result(c->run)->message);
    return fmi3OK;
}

/* ------------------------------------------------------------------ stepping */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean* eventHandlingNeeded, fmi3Boolean* terminateSimulation,
                      fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime)
{
    fsu* c = instance;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (in_state(c, "fmi3DoStep", IN(STEP))) return fmi3Error;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return say(c, fmi3Error, "%s: fmi3DoStep: a result pointer is NULL", c->name);
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = false;
    double now = fsr_stepper_time(c->run), dt = c->o.dt;
    *lastSuccessfulTime = now;
    if (!(communicationStepSize > 0.0) || !isfinite(communicationStepSize))
        return say(c, fmi3Error, "%s: fmi3DoStep: communicationStepSize = %g must be > 0", c->name,
                   communicationStepSize);
    if (!(fabs(currentCommunicationPoint - now) <= 1e-9 * (dt > fabs(now) ? dt : fabs(now))))
        return say(c, fmi3Error, "%s: fmi3DoStep: currentCommunicationPoint = %.17g s, but the FMU is at "
                   "%.17g s", c->name, currentCommunicationPoint, now);
    double target = currentCommunicationPoint + communicationStepSize;
    if (target > c->t_end + 1e-9 * (dt > c->t_end ? dt : c->t_end)) {
        if (c->stop_defined)
            return say(c, fmi3Error, "%s: fmi3DoStep: t = %.17g s is past stopTime = %.17g s, set in "
                       "fmi3EnterInitializationMode (FMI 3.0: no step beyond a defined stop time; give a "
                       "later one, or none)", c->name, target, c->t_end);
        return say(c, fmi3Error, "%s: fmi3DoStep: t = %.17g s is past the %ld steps of dt = %g s this "
                   "FMU can take (t <= %.17g s)", c->name, target, FSR_MAX_STEPS, dt, c->t_end);
    }
    if (c->retune) {
        c->retune = 0;
        if (fsr_stepper_retune(c->run) != FSR_OK) {
            c->state = FAILED;
            return say(c, fmi3Error, "%s: %s", c->name, fsr_stepper_result(c->run)->message);
        }
    }
    fsr_status st = fsr_stepper_advance(c->run, target);
    const fsr_result* r = fsr_stepper_result(c->run);
    if (st == FSR_BAD_OPTIONS)  /* the request was refused; the run is unchanged */
        return say(c, fmi3Error, "%s: fmi3DoStep: %s; the communication points must lie on the "
                   "internal step grid (fixedInternalStepSize)", c->name, r->message);
    if (st != FSR_OK) {
        c->state = FAILED;
        *terminateSimulation = true;
        *lastSuccessfulTime = r->t_stop;
        return say(c, fmi3Discard, "%s: %s", c->name, r->message);
    }
    *lastSuccessfulTime = fsr_stepper_time(c->run);
    return fmi3OK;
}

/* --------------------------------------------- everything else: not supported by this FMU */

#define NO_VARIABLES(T)                                                                               \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],         \
                          size_t nValueReferences, fmi3##T values[], size_t nValues)                  \
    {                                                                                                 \
        (void)valueReferences, (void)values, (void)nValues;                                           \
        return nValueReferences ? unsupported(instance, "fmi3Get" #T " (no variables of this type)")  \
                                : fmi3OK;                                                             \
    }                                                                                                 \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],         \
                          size_t nValueReferences, const fmi3##T values[], size_t nValues)            \
    {                                                                                                 \
        (void)valueReferences, (void)values, (void)nValues;                                           \
        return nValueReferences ? unsupported(instance, "fmi3Set" #T " (no variables of this type)")  \
                                : fmi3OK;                                                             \
    }
NO_VARIABLES(Float32)
NO_VARIABLES(Int8)
NO_VARIABLES(UInt8)
NO_VARIABLES(Int16)
NO_VARIABLES(UInt16)
NO_VARIABLES(Int32)
NO_VARIABLES(UInt32)
NO_VARIABLES(Int64)
NO_VARIABLES(UInt64)
NO_VARIABLES(Boolean)
NO_VARIABLES(String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)valueReferences, (void)valueSizes, (void)values, (void)nValues;
    return nValueReferences ? unsupported(instance, "fmi3GetBinary (no variables of this type)") : fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues)
{
    (void)valueReferences, (void)valueSizes, (void)values, (void)nValues;
    return nValueReferences ? unsupported(instance, "fmi3SetBinary (no variables of this type)") : fmi3OK;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[])
{
    (void)valueReferences, (void)values;
    return nValueReferences ? unsupported(instance, "fmi3GetClock (no clocks)") : fmi3OK;
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[])
{
    (void)valueReferences, (void)values;
    return nValueReferences ? unsupported(instance, "fmi3SetClock (no clocks)") : fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) { return unsupported(instance, "fmi3EnterEventMode"); }

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t* nDependencies)
{
    (void)valueReference, (void)nDependencies;
    return unsupported(instance, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent, (void)elementIndicesOfDependent, (void)independents, (void)elementIndicesOfIndependents;
    (void)dependencyKinds, (void)nDependencies;
    return unsupported(instance, "fmi3GetVariableDependencies");
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState)
{
    (void)FMUState;
    return unsupported(instance, "fmi3GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    (void)FMUState;
    return unsupported(instance, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState)
{
    (void)FMUState;
    return unsupported(instance, "fmi3FreeFMUState");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size)
{
    (void)FMUState, (void)size;
    return unsupported(instance, "fmi3SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    (void)FMUState, (void)serializedState, (void)size;
    return unsupported(instance, "fmi3SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState* FMUState)
{
    (void)serializedState, (void)size, (void)FMUState;
    return unsupported(instance, "fmi3DeserializeFMUState");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                        size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    return unsupported(instance, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                    const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                    size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    return unsupported(instance, "fmi3GetAdjointDerivative");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterConfigurationMode (no structural parameters)");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3ExitConfigurationMode (no structural parameters)");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences, (void)nValueReferences, (void)intervals, (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalDecimal (no clocks)");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions, (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalFraction (no clocks)");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return unsupported(instance, "fmi3GetShiftDecimal (no clocks)");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return unsupported(instance, "fmi3GetShiftFraction (no clocks)");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences, (void)nValueReferences, (void)intervals;
    return unsupported(instance, "fmi3SetIntervalDecimal (no clocks)");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return unsupported(instance, "fmi3SetIntervalFraction (no clocks)");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return unsupported(instance, "fmi3SetShiftDecimal (no clocks)");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return unsupported(instance, "fmi3SetShiftFraction (no clocks)");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EvaluateDiscreteStates (no event mode)");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate,
                                    fmi3Boolean* terminateSimulation,
                                    fmi3Boolean* nominalsOfContinuousStatesChanged,
                                    fmi3Boolean* valuesOfContinuousStatesChanged,
                                    fmi3Boolean* nextEventTimeDefined, fmi3Float64* nextEventTime)
{
    (void)discreteStatesNeedUpdate, (void)terminateSimulation, (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged, (void)nextEventTimeDefined, (void)nextEventTime;
    return unsupported(instance, "fmi3UpdateDiscreteStates (no event mode)");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    return unsupported(instance, "fmi3GetOutputDerivatives (maxOutputDerivativeOrder = 0)");
}

/* Model Exchange and Scheduled Execution: never instantiated (see fmi3Instantiate*). */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterContinuousTimeMode (Co-Simulation only)");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    return unsupported(instance, "fmi3CompletedIntegratorStep (Co-Simulation only)");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return unsupported(instance, "fmi3SetTime (Co-Simulation only)");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    return unsupported(instance, "fmi3SetContinuousStates (Co-Simulation only)");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives, (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStateDerivatives (Co-Simulation only)");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    (void)eventIndicators, (void)nEventIndicators;
    return unsupported(instance, "fmi3GetEventIndicators (Co-Simulation only)");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStates (Co-Simulation only)");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals, (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNominalsOfContinuousStates (Co-Simulation only)");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators)
{
    (void)nEventIndicators;
    return unsupported(instance, "fmi3GetNumberOfEventIndicators (Co-Simulation only)");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates)
{
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNumberOfContinuousStates (Co-Simulation only)");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference, (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition (Co-Simulation only)");
}
