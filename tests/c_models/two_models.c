/* Two generated models linked into one program: the one-beam variant `geometric` and the system
 * `hub` (generated/), each with its symbols named after it (fsm_geometric_*, fsm_hub_*).
 *     two_models T_END GEOMETRIC.csv HUB.csv
 * runs geometric, hub, then geometric again, each with the runtime's defaults (the driver's) up
 * to T_END, and writes the rows of each model as the driver does (%.17g, without the header).
 * Exit 1 when the two runs of geometric differ (one model's run must leave nothing behind),
 * 3 when a run fails. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flexsym/runtime.h"
#include "flexsym/system.h"

const fsm_system* fsm_geometric_model(void);
const fsm_system* fsm_hub_model(void);

static int run(const fsm_system* m, double t_end, fsr_result* r)
{
    double p[64], mp[64];
    fsr_options o;
    fsr_default_options(&o);
    memcpy(p, m->param_defaults, sizeof(double) * (size_t)m->np);
    memcpy(mp, m->drive_param_defaults, sizeof(double) * (size_t)m->nmp);
    o.p = p;
    o.mp = mp;
    o.t_end = t_end;
    return fsr_simulate(m, &o, r) == FSR_OK;
}

static int write_rows(const char* path, const fsr_result* r)
{
    FILE* f = fopen(path, "w");
    if (!f) return 0;
    for (int k = 0; k < r->nrows; ++k) {
        for (int j = 0; j < r->ncols; ++j)
            fprintf(f, j ? ",%.17g" : "%.17g", r->rows[(size_t)k * (size_t)r->ncols + j]);
        fputc('\n', f);
    }
    return fclose(f) == 0;
}

int main(int argc, char** argv)
{
    if (argc != 4) return 2;
    double t_end = atof(argv[1]);
    fsr_result a, b, again;
    if (!run(fsm_geometric_model(), t_end, &a) || !run(fsm_hub_model(), t_end, &b) ||
        !run(fsm_geometric_model(), t_end, &again))
        return 3;
    if (!write_rows(argv[2], &a) || !write_rows(argv[3], &b)) return 3;
    int same = a.nrows == again.nrows && a.ncols == again.ncols &&
               !memcmp(a.rows, again.rows, sizeof(double) * (size_t)a.nrows * (size_t)a.ncols);
    printf("{\"geometric\": [%d, %d], \"hub\": [%d, %d], \"repeat_identical\": %d}\n", a.nrows, a.ncols,
           b.nrows, b.ncols, same);
    fsr_free(&a);
    fsr_free(&b);
    fsr_free(&again);
    return same ? 0 : 1;
}
