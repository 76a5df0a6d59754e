/* The integrator registry: the one list of the runtime's integrators, one line each,
 *     FSR_INTEGRATOR(name, NAME, code, capabilities)
 * name: the word of --integrator, its source file src/<name>.c and the descriptor that file
 * gives, fsr_integrator_<name>() (src/integrator.h); NAME: its fsr_method constant FSR_<NAME>
 * (runtime.h); code: that constant's value (in-process runs pass it as a number, so a code is
 * never reused); capabilities: FSR_CAP_* (runtime.h), what the Python side checks before a build
 * and the run loop dispatches on. The lines are in the order the documentation lists them.
 *
 * Read by the C preprocessor (runtime.h's enum, simulate.c's table: define FSR_INTEGRATOR, then
 * include this file; it has no include guard), by CMake (flexsym_runtime.cmake compiles
 * src/<name>.c) and by Python (flexsym/model/integrators.py parses these lines: the
 * --integrator choices, the codes, the options that apply, what an FMU offers). So adding an
 * integrator is its file plus one line here.
 */
FSR_INTEGRATOR(rk4, RK4, 0, FSR_CAP_FIXED_GRID)
FSR_INTEGRATOR(dopri5, DOPRI5, 3, FSR_CAP_ADAPTIVE)
FSR_INTEGRATOR(genalpha, GENALPHA, 1, FSR_CAP_IMPLICIT | FSR_CAP_FIXED_GRID | FSR_CAP_DRIVE_INPUT)
FSR_INTEGRATOR(newmark, NEWMARK, 2, FSR_CAP_IMPLICIT | FSR_CAP_FIXED_GRID | FSR_CAP_DRIVE_INPUT)
FSR_INTEGRATOR(radau5, RADAU5, 4, FSR_CAP_IMPLICIT | FSR_CAP_DRIVE_INPUT)
FSR_INTEGRATOR(ali3p, ALI3P, 5, FSR_CAP_CONSTRAINED | FSR_CAP_IMPLICIT | FSR_CAP_FIXED_GRID)
FSR_INTEGRATOR(genalpha3, GENALPHA3, 6, FSR_CAP_CONSTRAINED | FSR_CAP_IMPLICIT | FSR_CAP_FIXED_GRID)
FSR_INTEGRATOR(rk4p, RK4P, 7, FSR_CAP_CONSTRAINED | FSR_CAP_FIXED_GRID)
