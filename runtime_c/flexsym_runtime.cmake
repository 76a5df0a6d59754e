# Included by every generated variant's CMakeLists.txt (see templates/CMakeLists.txt.j2).
# flexsym_add_model(NAME ACCESSOR sources...) builds, from a model's sources plus this runtime:
#   flexsym_NAME      the command-line driver (src/driver.c) of that model
#   libflexsym_NAME   a shared library exposing ACCESSOR, the kernels, fsr_simulate and fsr_batch
#                     (tests, Python)
# The sources (a generated folder's, or hand-written ones) define `const fsm_system* ACCESSOR(void)`
# (system.h; a generated folder's is fsm_NAME_model) and name every other global symbol after the
# model, so several models link into one program: flexsym_add_model_objects(NAME sources...)
# gives a model's objects alone (flexsym_NAME_objects), to link with flexsym_runtime and others.
set(FLEXSYM_RUNTIME_DIR "${CMAKE_CURRENT_LIST_DIR}")
# The run loop (simulate.c), one file per integrator of the registry (include/flexsym/
# integrators.h: src/<name>.c for each line) and what they share.
file(STRINGS "${FLEXSYM_RUNTIME_DIR}/include/flexsym/integrators.h" _flexsym_registry REGEX "^FSR_INTEGRATOR\\(")
set(FLEXSYM_RUNTIME_SOURCES)
foreach(line ${_flexsym_registry})
  string(REGEX REPLACE "^FSR_INTEGRATOR\\(([a-z0-9_]+),.*" "\\1" integrator "${line}")
  list(APPEND FLEXSYM_RUNTIME_SOURCES "${FLEXSYM_RUNTIME_DIR}/src/${integrator}.c")
endforeach()
foreach(f simulate.c batch.c erk.c newton.c ode.c constrained.c common.c linalg.c)
  list(APPEND FLEXSYM_RUNTIME_SOURCES "${FLEXSYM_RUNTIME_DIR}/src/${f}")
endforeach()

if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE Release)
endif()

# The flags of every model build: the driver, the shared library and an FMU compute the same
# rows bit for bit only when compiled alike. The runtime's loops run over a few coordinates
# (3 to 65): vector code costs more than it saves there (measured: 5-13 % faster integration
# of #1-#3 without it, ef 3 %).
# A generated system.c initialises fsm_system positionally and ends before the fields a model
# needs not give (system.h: band_first, band_end; C zero-fills them), so that adding such a
# field leaves the files of every model that does not use it unchanged.
set(FLEXSYM_WARNINGS -Wall -Wextra -Werror -pedantic -Wno-missing-field-initializers)
set(FLEXSYM_CODEGEN $<$<C_COMPILER_ID:GNU,Clang,AppleClang>:-fno-tree-vectorize>)

function(_flexsym_objects target)
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON C_STANDARD 99
                        C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_include_directories(${target} PUBLIC "${FLEXSYM_RUNTIME_DIR}/include")
  target_compile_options(${target} PUBLIC ${FLEXSYM_WARNINGS})
  target_compile_options(${target} PRIVATE ${FLEXSYM_CODEGEN})
endfunction()

# The runtime, compiled once per project and linked with every model of it; or, given
# FLEXSYM_RUNTIME_OBJECTS (flexsym's own builds: toolchain/build.py), the objects of a build of
# this very target with the same compiler and flags, compiled once for every model.
if(NOT TARGET flexsym_runtime)
  if(FLEXSYM_RUNTIME_OBJECTS)
    add_library(flexsym_runtime OBJECT IMPORTED)
    set_target_properties(flexsym_runtime PROPERTIES IMPORTED_OBJECTS "${FLEXSYM_RUNTIME_OBJECTS}")
  else()
    add_library(flexsym_runtime OBJECT ${FLEXSYM_RUNTIME_SOURCES})
    _flexsym_objects(flexsym_runtime)
    set_target_properties(flexsym_runtime PROPERTIES EXCLUDE_FROM_ALL ON)  # built when linked (not by an FMU)
  endif()
endif()

# flexsym_NAME_objects: the model's sources, each with its own folder on the include path (a
# generated folder's header)
function(flexsym_add_model_objects name)
  set(objs flexsym_${name}_objects)
  add_library(${objs} OBJECT ${ARGN})
  _flexsym_objects(${objs})
  _flexsym_source_dirs(${objs} ${ARGN})
endfunction()

function(_flexsym_source_dirs target)
  foreach(src ${ARGN})
    get_filename_component(dir "${src}" ABSOLUTE)
    get_filename_component(dir "${dir}" DIRECTORY)
    target_include_directories(${target} PRIVATE "${dir}")
  endforeach()
endfunction()

# flexsym_add_kernels(NAME sources...): a model's kernels, compiled apart from its other sources
# (flexsym_NAME_kernels, their objects listed in kernels_objects.txt), which
# flexsym_add_model(NAME ...) links before them. Given FLEXSYM_KERNELS_OBJECTS (flexsym's own
# builds: toolchain/build.py), the objects of an earlier build of this very target, kept for
# every folder with the same kernels (a system's folders that differ in its run-time
# parameters' values alone).
function(flexsym_add_kernels name)
  set(kernels flexsym_${name}_kernels)
  if(FLEXSYM_KERNELS_OBJECTS)
    add_library(${kernels} OBJECT IMPORTED)
    set_target_properties(${kernels} PROPERTIES IMPORTED_OBJECTS "${FLEXSYM_KERNELS_OBJECTS}")
  else()
    add_library(${kernels} OBJECT ${ARGN})
    _flexsym_objects(${kernels})
    _flexsym_source_dirs(${kernels} ${ARGN})
    file(GENERATE OUTPUT "${CMAKE_BINARY_DIR}/kernels_objects.txt"
         CONTENT "$<JOIN:$<TARGET_OBJECTS:${kernels}>,\n>\n")
  endif()
endfunction()

function(flexsym_add_model name accessor)
  flexsym_add_model_objects(${name} ${ARGN})
  set(objs flexsym_${name}_objects)
  if(TARGET flexsym_${name}_kernels)
    set(objs flexsym_${name}_kernels ${objs})
  endif()
  add_executable(flexsym_${name} "${FLEXSYM_RUNTIME_DIR}/src/driver.c")
  set_target_properties(flexsym_${name} PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON
                        C_EXTENSIONS OFF)
  # the one place a driver learns its model
  target_compile_definitions(flexsym_${name} PRIVATE FSM_MODEL=${accessor})
  target_link_libraries(flexsym_${name} PRIVATE ${objs} flexsym_runtime m)

  list(TRANSFORM objs REPLACE "(.+)" "$<TARGET_OBJECTS:\\1>" OUTPUT_VARIABLE objects)
  add_library(flexsym_${name}_shared SHARED ${objects} $<TARGET_OBJECTS:flexsym_runtime>)
  set_target_properties(flexsym_${name}_shared PROPERTIES OUTPUT_NAME flexsym_${name})
  target_link_libraries(flexsym_${name}_shared PRIVATE m)
endfunction()

# flexsym_add_fmu(ID CONFIG_DIR sources...) builds ID.so, the binary of an FMI 3.0 Co-Simulation
# FMU (runtime_c/fmi3, flexsym/sim/fmu.py): the model's sources, this runtime and the fmi3 wrapper,
# compiled with the flags of flexsym_add_model (so its rows equal the driver's bit for bit);
# only the fmi3* functions are exported. The model's accessor is FSU_MODEL of CONFIG_DIR's
# flexsym_fmu_config.h. Given FLEXSYM_FMU_RUNTIME_OBJECTS (flexsym's own exports:
# flexsym/sim/fmu.py), the runtime's objects compiled once with these flags
# (-fvisibility=hidden: build.FMU_FLAGS) instead of its sources.
function(flexsym_add_fmu id config_dir)
  if(FLEXSYM_FMU_RUNTIME_OBJECTS)
    set(runtime ${FLEXSYM_FMU_RUNTIME_OBJECTS})
  else()
    set(runtime ${FLEXSYM_RUNTIME_SOURCES})
  endif()
  add_library(${id} MODULE ${ARGN} ${runtime} "${FLEXSYM_RUNTIME_DIR}/fmi3/fmi3_flexsym.c")
  set_target_properties(${id} PROPERTIES PREFIX "" C_STANDARD 99 C_STANDARD_REQUIRED ON
                        C_EXTENSIONS OFF C_VISIBILITY_PRESET hidden)
  target_include_directories(${id} PRIVATE "${FLEXSYM_RUNTIME_DIR}/include" "${FLEXSYM_RUNTIME_DIR}/fmi3"
                             "${config_dir}")
  target_compile_options(${id} PRIVATE ${FLEXSYM_WARNINGS} ${FLEXSYM_CODEGEN})
  target_link_libraries(${id} PRIVATE m)
endfunction()
