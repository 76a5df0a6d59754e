/* DO NOT EDIT: written by `python -m flexsym.model.options > runtime_c/include/flexsym/limits.h`
 * from the option table in flexsym/model/options.py (the one place for run limits and
 * defaults). The runtime refuses runs beyond these limits as a last line of defence. */
#ifndef FLEXSYM_LIMITS_H
#define FLEXSYM_LIMITS_H

#define FSR_MAX_STEPS 100000000L
#define FSR_MAX_ROWS 10000000L
#define FSR_MAX_ROW_BYTES 1073741824L
#define FSR_MAX_REPEAT 1000L
#define FSR_DEFAULT_T_END 20.0
#define FSR_DEFAULT_DT 0.001
#define FSR_DEFAULT_TOL 1e-06
#define FSR_DEFAULT_MAX_STEPS 1000000L
#define FSR_DEFAULT_NEWTON_TOL 1e-12
#define FSR_DEFAULT_RHO_INF 0.9
#define FSR_DEFAULT_NEWMARK_GAMMA 0.5
#define FSR_DEFAULT_NEWMARK_BETA 0.25
#define FSR_DEFAULT_BLOWUP 10.0
#define FSR_DEFAULT_PENALTY 10000000.0

#endif
