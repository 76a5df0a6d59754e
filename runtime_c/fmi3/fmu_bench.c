/* Time an FMU's doStep loop as an importer runs it (flexsym bench-fmu, flexsym/sim/fmu.py):
 *
 *   fmu_bench BINARY.so TOKEN T_END H REPEAT VR...
 *
 * Each run: instantiate, initialize (stop time T_END), then doStep by H up to T_END, reading the
 * Float64 variables VR... after every step; free. Prints one JSON line with the CPU time per run
 * (median, min, max of REPEAT runs after a warm-up) and the last values read.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi3.h"

#define MAX_VR 256
#define MAX_REPEAT 1000

typedef fmi3Instance (*instantiate_fn)(fmi3String, fmi3String, fmi3String, fmi3Boolean, fmi3Boolean, fmi3Boolean,
                                       fmi3Boolean, const fmi3ValueReference[], size_t, fmi3InstanceEnvironment,
                                       fmi3LogMessageCallback, fmi3IntermediateUpdateCallback);
typedef fmi3Status (*enter_init_fn)(fmi3Instance, fmi3Boolean, fmi3Float64, fmi3Float64, fmi3Boolean, fmi3Float64);
typedef fmi3Status (*instance_fn)(fmi3Instance);
typedef void (*free_fn)(fmi3Instance);
typedef fmi3Status (*get_fn)(fmi3Instance, const fmi3ValueReference[], size_t, fmi3Float64[], size_t);
typedef fmi3Status (*step_fn)(fmi3Instance, fmi3Float64, fmi3Float64, fmi3Boolean, fmi3Boolean*, fmi3Boolean*,
                              fmi3Boolean*, fmi3Float64*);

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env, (void)status, (void)category;
    fprintf(stderr, "fmu_bench: %s\n", message);
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void* a, const void* b)
{
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

int main(int argc, char** argv)
{
    if (argc < 6) {
        fprintf(stderr, "usage: fmu_bench BINARY.so TOKEN T_END H REPEAT VR...\n");
        return 2;
    }
    double t_end = atof(argv[3]), h = atof(argv[4]);
    int repeat = atoi(argv[5]), nvr = argc - 6;
    if (!(t_end > 0 && h > 0) || repeat < 1 || repeat > MAX_REPEAT || nvr > MAX_VR) {
        fprintf(stderr, "fmu_bench: bad T_END, H, REPEAT or too many VR\n");
        return 2;
    }
    fmi3ValueReference vr[MAX_VR];
    fmi3Float64 val[MAX_VR];
    for (int i = 0; i < nvr; ++i) vr[i] = (fmi3ValueReference)atol(argv[6 + i]);
    void* lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "fmu_bench: %s\n", dlerror());
        return 2;
    }
    /* object pointer to function pointer: POSIX guarantees it works for dlsym */
#define SYM(T, name) T name; *(void**)(&name) = dlsym(lib, #name)
    SYM(instantiate_fn, fmi3InstantiateCoSimulation);
    SYM(enter_init_fn, fmi3EnterInitializationMode);
    SYM(instance_fn, fmi3ExitInitializationMode);
    SYM(instance_fn, fmi3Terminate);
    SYM(free_fn, fmi3FreeInstance);
    SYM(get_fn, fmi3GetFloat64);
    SYM(step_fn, fmi3DoStep);
    if (!fmi3InstantiateCoSimulation || !fmi3EnterInitializationMode || !fmi3ExitInitializationMode ||
        !fmi3Terminate || !fmi3FreeInstance || !fmi3GetFloat64 || !fmi3DoStep) {
        fprintf(stderr, "fmu_bench: %s lacks an fmi3 function\n", argv[1]);
        return 2;
    }
    long steps = (long)(t_end / h + 0.5);
    double times[MAX_REPEAT + 1];
    for (int k = 0; k <= repeat; ++k) {  /* k = 0: warm-up */
        double t0 = cpu_seconds();
        fmi3Instance c = fmi3InstantiateCoSimulation("bench", argv[2], NULL, false, false, false, false, NULL, 0,
                                                     NULL, logger, NULL);
        if (!c || fmi3EnterInitializationMode(c, false, 0.0, 0.0, true, t_end) ||
            fmi3ExitInitializationMode(c))
            return 3;
        for (long j = 0; j < steps; ++j) {
            fmi3Boolean event, terminate, early;
            fmi3Float64 last;
            if (fmi3DoStep(c, (double)j * h, h, true, &event, &terminate, &early, &last) ||
                fmi3GetFloat64(c, vr, (size_t)nvr, val, (size_t)nvr))
                return 3;
        }
        fmi3Terminate(c);
        fmi3FreeInstance(c);
        times[k] = cpu_seconds() - t0;
    }
    qsort(times + 1, (size_t)repeat, sizeof(double), cmp_double);
    printf("{\"steps\": %ld, \"repeat\": %d, \"cpu_median\": %.9g, \"cpu_min\": %.9g, \"cpu_max\": %.9g, "
           "\"last\": %.17g}\n", steps, repeat, times[1 + repeat / 2], times[1], times[repeat],
           nvr ? val[0] : 0.0);
    dlclose(lib);
    return 0;
}
