/* fsr_factor_failed (common.c): what a failed factorization of an implicit integrator's Newton
 * or iteration matrix reports (tests/test_bordered_band.py). Prints "status|message" for: a
 * matrix with a NaN, a finite matrix after a Newton update beyond blowup x L, the same after a
 * small update, and one before any update. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "common.h"

static void report(double a00, double dq)
{
    fsr_result r;
    fsr_options o;
    memset(&r, 0, sizeof r);
    memset(&o, 0, sizeof o);
    o.blowup = 10.0;
    double A[4] = {a00, 0.0, 0.0, 0.0};
    fsr_status st = fsr_factor_failed(&r, &o, 0.5, A, 2, dq, 0.25, "genalpha3: iteration matrix");
    printf("%d|%s\n", (int)st, r.message);
}

int main(void)
{
    report(NAN, 0.0);
    report(1.0, 2.4e99);
    report(1.0, 1e-3);
    report(1.0, 0.0);
    return 0;
}
