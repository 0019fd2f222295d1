/* A portable FMI 2.0 co-simulation master: loads a controller FMU and a plant
 * FMU from their unpacked folders (the binary of the platform it was built
 * for, dlopen or LoadLibrary), couples them as the demo does and runs the
 * paper's scenario (every joint from 0.05 rad at rest, communication step
 * 25 ms, the controller stepped first). It knows no model: the value
 * references come from each modelDescription.xml by name, so it runs any
 * exported pair of any joint count. The same source is built with gcc
 * (linux64), mingw (win64, run under wine) and the aarch64 cross compiler
 * (run under qemu-user), and the figures it prints are compared.
 *
 * Usage: fmu_master PLATFORM CONTROLLER_DIR PLANT_DIR STOP_TIME
 * Prints one line: "joints N band T final_energy E e_ref R" (T = -1 when the
 * energy never stays in the 5 % band). Exit code 0, or 1 with a message. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

#ifdef _WIN32
#include <windows.h>
#define LIBRARY_SUFFIX ".dll"
typedef HMODULE library_t;
static library_t open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(library_t lib, const char *name) {
    return (void *)(size_t)GetProcAddress(lib, name);
}
#else
#include <dlfcn.h>
#define LIBRARY_SUFFIX ".so"
typedef void *library_t;
static library_t open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(library_t lib, const char *name) { return dlsym(lib, name); }
#endif

#define MAX_JOINTS 16
#define STEP 0.025
#define START_ANGLE 0.05

static void fail(const char *format, ...) {
    va_list args;
    va_start(args, format);
    fprintf(stderr, "fmu_master: ");
    vfprintf(stderr, format, args);
    fprintf(stderr, "\n");
    va_end(args);
    exit(1);
}

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    if (status < fmi2Warning) return;
    char text[2048];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    fprintf(stderr, "  [%s] %s: %s\n", category, name, text);
}

static char *read_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) fail("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    if (!text || fread(text, 1, (size_t)n, f) != (size_t)n) fail("cannot read %s", path);
    text[n] = '\0';
    fclose(f);
    return text;
}

/* The value of attribute `key` (e.g. `guid="`) after `from`, copied to out. */
static int attribute(const char *from, const char *key, char *out, size_t size) {
    const char *p = strstr(from, key);
    if (!p) return 0;
    p += strlen(key);
    const char *end = strchr(p, '"');
    if (!end || (size_t)(end - p) >= size) return 0;
    memcpy(out, p, (size_t)(end - p));
    out[end - p] = '\0';
    return 1;
}

/* The value reference of the variable `name`, or -1. */
static long value_reference(const char *xml, const char *name) {
    char needle[128];
    snprintf(needle, sizeof needle, "<ScalarVariable name=\"%s\"", name);
    const char *p = strstr(xml, needle);
    char vr[32];
    if (!p || !attribute(p, "valueReference=\"", vr, sizeof vr)) return -1;
    return strtol(vr, NULL, 10);
}

typedef struct {
    char identifier[256];
    char guid[128];
    char resources[4096];
    char *xml;
    library_t library;
    fmi2Component c;
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup_experiment;
    fmi2EnterInitializationModeTYPE *enter_initialization;
    fmi2ExitInitializationModeTYPE *exit_initialization;
    fmi2SetRealTYPE *set_real;
    fmi2GetRealTYPE *get_real;
    fmi2DoStepTYPE *do_step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
} Fmu;

/* `file:///dir/resources` of an unpacked FMU folder (an absolute path; on
 * Windows `C:\dir` becomes `file:///C:/dir`). */
static void resource_uri(const char *dir, char *out, size_t size) {
    char path[3072];
    snprintf(path, sizeof path, "%s/resources", dir);
    for (char *p = path; *p; p++)
        if (*p == '\\') *p = '/';
    snprintf(out, size, "file://%s%s", path[0] == '/' ? "" : "/", path);
}

#define LOAD(fmu, field, name)                                                     \
    do {                                                                           \
        *(void **)&(fmu)->field = symbol((fmu)->library, name);                    \
        if (!(fmu)->field) fail("%s: no symbol %s", (fmu)->identifier, name);      \
    } while (0)

static void load(Fmu *fmu, const char *platform, const char *dir) {
    char path[4096];
    snprintf(path, sizeof path, "%s/modelDescription.xml", dir);
    fmu->xml = read_file(path);
    if (!attribute(fmu->xml, "modelIdentifier=\"", fmu->identifier, sizeof fmu->identifier) ||
        !attribute(fmu->xml, "guid=\"", fmu->guid, sizeof fmu->guid))
        fail("%s: no modelIdentifier or guid", path);
    snprintf(path, sizeof path, "%s/binaries/%s/%s%s", dir, platform, fmu->identifier,
             LIBRARY_SUFFIX);
    fmu->library = open_library(path);
    if (!fmu->library) fail("cannot load %s", path);
    resource_uri(dir, fmu->resources, sizeof fmu->resources);
    LOAD(fmu, instantiate, "fmi2Instantiate");
    LOAD(fmu, setup_experiment, "fmi2SetupExperiment");
    LOAD(fmu, enter_initialization, "fmi2EnterInitializationMode");
    LOAD(fmu, exit_initialization, "fmi2ExitInitializationMode");
    LOAD(fmu, set_real, "fmi2SetReal");
    LOAD(fmu, get_real, "fmi2GetReal");
    LOAD(fmu, do_step, "fmi2DoStep");
    LOAD(fmu, terminate, "fmi2Terminate");
    LOAD(fmu, free_instance, "fmi2FreeInstance");
}

static fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};

static void check(const Fmu *fmu, fmi2Status status, const char *call) {
    if (status != fmi2OK && status != fmi2Warning)
        fail("%s: %s returned status %d", fmu->identifier, call, (int)status);
}

/* The value references of `base[1]`, `base[2]`, ...; returns the count. */
static size_t joint_refs(const Fmu *fmu, const char *base, fmi2ValueReference *out) {
    size_t n = 0;
    for (; n < MAX_JOINTS; n++) {
        char name[64];
        snprintf(name, sizeof name, "%s[%zu]", base, n + 1);
        long vr = value_reference(fmu->xml, name);
        if (vr < 0) break;
        out[n] = (fmi2ValueReference)vr;
    }
    return n;
}

static fmi2ValueReference named_ref(const Fmu *fmu, const char *name) {
    long vr = value_reference(fmu->xml, name);
    if (vr < 0) fail("%s: no variable %s", fmu->identifier, name);
    return (fmi2ValueReference)vr;
}

int main(int argc, char **argv) {
    if (argc != 5) fail("usage: fmu_master PLATFORM CONTROLLER_DIR PLANT_DIR STOP_TIME");
    Fmu controller = {0}, plant = {0};
    load(&controller, argv[1], argv[2]);
    load(&plant, argv[1], argv[3]);
    double stop = atof(argv[4]);

    /* Plant outputs q, qd, energy; inputs tau; parameters q0. Controller
     * inputs q, qd; outputs tau. */
    fmi2ValueReference plant_state[2 * MAX_JOINTS], ctrl_state[2 * MAX_JOINTS];
    fmi2ValueReference plant_tau[MAX_JOINTS], ctrl_tau[MAX_JOINTS], q0[MAX_JOINTS];
    size_t n = joint_refs(&plant, "q", plant_state);
    if (n == 0 || joint_refs(&plant, "qd", plant_state + n) != n ||
        joint_refs(&plant, "tau", plant_tau) != n || joint_refs(&plant, "q0", q0) != n ||
        joint_refs(&controller, "q", ctrl_state) != n ||
        joint_refs(&controller, "qd", ctrl_state + n) != n ||
        joint_refs(&controller, "tau", ctrl_tau) != n)
        fail("the controller and the plant disagree on the joints");
    fmi2ValueReference energy = named_ref(&plant, "energy");
    fmi2ValueReference e_ref_vr = named_ref(&controller, "E_ref");

    Fmu *both[2] = {&plant, &controller};
    for (int i = 0; i < 2; i++) {
        Fmu *f = both[i];
        f->c = f->instantiate(f->identifier, fmi2CoSimulation, f->guid, f->resources, &callbacks,
                              fmi2False, fmi2False);
        if (!f->c) fail("%s: fmi2Instantiate failed", f->identifier);
        /* No stop time: the controller also steps at the last sample. */
        check(f, f->setup_experiment(f->c, fmi2False, 0.0, 0.0, fmi2False, 0.0),
              "fmi2SetupExperiment");
        check(f, f->enter_initialization(f->c), "fmi2EnterInitializationMode");
    }
    double start[MAX_JOINTS];
    for (size_t j = 0; j < n; j++) start[j] = START_ANGLE;
    check(&plant, plant.set_real(plant.c, q0, n, start), "fmi2SetReal(q0)");
    check(&plant, plant.exit_initialization(plant.c), "fmi2ExitInitializationMode");
    double y[2 * MAX_JOINTS], tau[MAX_JOINTS], e, e_ref;
    check(&plant, plant.get_real(plant.c, plant_state, 2 * n, y), "fmi2GetReal");
    /* The first solve, at fmi2ExitInitializationMode, uses these inputs. */
    check(&controller, controller.set_real(controller.c, ctrl_state, 2 * n, y), "fmi2SetReal");
    check(&controller, controller.exit_initialization(controller.c),
          "fmi2ExitInitializationMode");
    check(&controller, controller.get_real(controller.c, &e_ref_vr, 1, &e_ref), "fmi2GetReal");

    long steps = lround(stop / STEP);
    double band = -1.0;
    int inside = 0;
    for (long k = 0; k <= steps; k++) {
        double t = (double)k * STEP;
        check(&plant, plant.get_real(plant.c, plant_state, 2 * n, y), "fmi2GetReal");
        check(&plant, plant.get_real(plant.c, &energy, 1, &e), "fmi2GetReal");
        if (fabs(e - e_ref) >= 0.05 * fabs(e_ref) || !isfinite(e)) {
            inside = 0;
        } else if (!inside) {
            inside = 1;
            band = t;
        }
        if (k > 0)
            check(&controller, controller.set_real(controller.c, ctrl_state, 2 * n, y),
                  "fmi2SetReal");
        check(&controller, controller.do_step(controller.c, t, STEP, fmi2True), "fmi2DoStep");
        check(&controller, controller.get_real(controller.c, ctrl_tau, n, tau), "fmi2GetReal");
        if (k == steps) break;
        check(&plant, plant.set_real(plant.c, plant_tau, n, tau), "fmi2SetReal");
        check(&plant, plant.do_step(plant.c, t, STEP, fmi2True), "fmi2DoStep");
    }
    for (int i = 0; i < 2; i++) {
        check(both[i], both[i]->terminate(both[i]->c), "fmi2Terminate");
        both[i]->free_instance(both[i]->c);
    }
    printf("joints %zu band %.3f final_energy %.9f e_ref %.6f\n", n, inside ? band : -1.0, e,
           e_ref);
    return 0;
}
