/* A minimal FMI 2.0 co-simulation host with no Python of its own (docs/fmu.md).

   It loads the binary of an exported actuator FMU, holds the piston still with the valve
   at 7 V for 0.5 s in steps of 1 ms, and prints the force and the chamber pressures: the
   same run as the first FMPy example of docs/fmu.md. The value references are the FMU's
   fixed ones (valve_voltage 0, piston_force 3, cap_pressure 6, rod_pressure 7).

   Build and run on Linux, from the folder holding gamma.fmu (pneumaquad export fmu
   --params crr-gamma -o gamma.fmu), with the Python that has pneumaquad installed:

     gcc -o fmu_host docs/examples/fmu_host.c -ldl
     mkdir gamma && (cd gamma && unzip -q ../gamma.fmu)
     LIBPYTHON=$(python3 -c 'import sysconfig; print(sysconfig.get_config_var("LIBDIR"))')
     SEARCH=$(python3 -c 'import os, sys; print(os.pathsep.join(p for p in sys.path if p))')
     LD_PRELOAD=$LIBPYTHON/libpython3.11.so PYTHONPATH=$SEARCH ./fmu_host \
         gamma/binaries/linux64/pneumaquad_crr_gamma.so \
         "$(grep -o 'guid="[^"]*"' gamma/modelDescription.xml | cut -d'"' -f2)" \
         "file://$PWD/gamma/resources"

   (python3: the Python of the environment pneumaquad is installed in; LD_PRELOAD, because
   pythonfmu's binary does not link Python itself; PYTHONPATH, the module search path of that
   Python, because the interpreter the binary starts does not know the environment.) */

#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

typedef void *fmi2Component;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Boolean;
typedef int fmi2Status; /* 0 ok, 1 warning, 2 discard, 3 error, 4 fatal */

typedef struct {
    void (*logger)(void *, const char *, fmi2Status, const char *, const char *, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static void print_message(void *environment, const char *instance, fmi2Status status,
                          const char *category, const char *message, ...) {
    va_list arguments;
    (void)environment;
    va_start(arguments, message);
    printf("[%s, status %d, %s] ", instance, status, category);
    vprintf(message, arguments);
    printf("\n");
    va_end(arguments);
}

static void *function(void *library, const char *name) {
    void *found = dlsym(library, name);
    if (found == NULL) {
        printf("%s not found in the FMU's binary\n", name);
        exit(1);
    }
    return found;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        printf("usage: %s BINARY GUID RESOURCES_URI\n", argv[0]);
        return 2;
    }
    void *library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        printf("cannot load %s: %s\n", argv[1], dlerror());
        return 1;
    }
    fmi2Component (*instantiate)(const char *, int, const char *, const char *,
                                 const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean) =
        function(library, "fmi2Instantiate");
    fmi2Status (*setup_experiment)(fmi2Component, fmi2Boolean, double, double, fmi2Boolean,
                                   double) = function(library, "fmi2SetupExperiment");
    fmi2Status (*enter_initialization)(fmi2Component) =
        function(library, "fmi2EnterInitializationMode");
    fmi2Status (*exit_initialization)(fmi2Component) =
        function(library, "fmi2ExitInitializationMode");
    fmi2Status (*set_real)(fmi2Component, const fmi2ValueReference *, size_t, const double *) =
        function(library, "fmi2SetReal");
    fmi2Status (*get_real)(fmi2Component, const fmi2ValueReference *, size_t, double *) =
        function(library, "fmi2GetReal");
    fmi2Status (*do_step)(fmi2Component, double, double, fmi2Boolean) =
        function(library, "fmi2DoStep");
    fmi2Status (*terminate)(fmi2Component) = function(library, "fmi2Terminate");
    void (*free_instance)(fmi2Component) = function(library, "fmi2FreeInstance");

    fmi2CallbackFunctions callbacks = {print_message, calloc, free, NULL, NULL};
    const int co_simulation = 1;
    fmi2Component actuator =
        instantiate("actuator", co_simulation, argv[2], argv[3], &callbacks, 0, 0);
    if (actuator == NULL) {
        printf("instantiation failed\n");
        return 1;
    }
    const fmi2ValueReference valve_voltage = 0;
    const fmi2ValueReference outputs[3] = {3, 6, 7}; /* force, cap and rod pressure */
    const double voltage = 7.0, step = 1e-3;
    double values[3];
    fmi2Status status = setup_experiment(actuator, 0, 0.0, 0.0, 0, 0.0);
    status |= enter_initialization(actuator);
    status |= set_real(actuator, &valve_voltage, 1, &voltage);
    status |= exit_initialization(actuator);
    for (int n = 0; n < 500 && status == 0; n++) {
        status = do_step(actuator, n * step, step, 1);
    }
    status |= get_real(actuator, outputs, 3, values);
    printf("status %d: force %.1f N, cap %.3f bar, rod %.3f bar\n", status, values[0],
           values[1] / 1e5, values[2] / 1e5);
    terminate(actuator);
    free_instance(actuator);
    dlclose(library);
    return status == 0 ? 0 : 1;
}
