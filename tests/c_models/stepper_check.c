/* The four-bar's rows of a run advanced step by step (fsr_stepper: one grid point at a time, and three at
 * a time) against fsr_simulate's, bit for bit.  stepper_check ali3p|genalpha3 DT T_END
 * prints one JSON line; exit 0 when every row is identical. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flexsym/runtime.h"
#include "flexsym/system.h"

const fsm_system* fsm_fourbar_model(void);

int main(int argc, char** argv)
{
    if (argc != 4) return 2;
    const fsm_system* m = fsm_fourbar_model();
    double p[32], mp[32];
    memcpy(p, m->param_defaults, sizeof(double) * (size_t)m->np);
    memcpy(mp, m->drive_param_defaults, sizeof(double) * (size_t)m->nmp);
    fsr_options o;
    fsr_default_options(&o);
    o.method = strcmp(argv[1], "ali3p") ? FSR_GENALPHA3 : FSR_ALI3P;
    o.dt = atof(argv[2]);
    o.t_end = atof(argv[3]);
    o.p = p;
    o.mp = mp;
    fsr_result r;
    if (fsr_simulate(m, &o, &r)) return 3;
    long compared = 0, differ = 0;
    for (int stride = 1; stride <= 3; stride += 2) {
        fsr_stepper* st = fsr_stepper_new(m, &o, NULL);
        if (!st || fsr_stepper_result(st)->status) return 3;
        for (int k = 0; k < r.nrows; k += stride) {
            if (k && fsr_stepper_advance(st, r.rows[(size_t)k * (size_t)r.ncols])) return 3;
            const fsr_result* s = fsr_stepper_result(st);
            compared++;
            if (s->ncols != r.ncols || memcmp(s->rows, r.rows + (size_t)k * (size_t)r.ncols,
                                              sizeof(double) * (size_t)r.ncols))
                differ++;
        }
        fsr_stepper_free(st);
    }
    printf("{\"rows\": %d, \"compared\": %ld, \"differ\": %ld}\n", r.nrows, compared, differ);
    fsr_free(&r);
    return differ ? 1 : 0;
}
