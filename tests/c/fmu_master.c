/* A portable FMI 2.0 and FMI 3.0 co-simulation master: loads a controller
 * FMU and a plant FMU from their unpacked folders (the binary of the
 * platform it was built for, dlopen or LoadLibrary), couples them as the
 * demo does and runs the paper's scenario (every joint from 0.05 rad at
 * rest, communication step 25 ms, the controller stepped first). It knows
 * no model: the FMI version (fmiVersion) and the value references come from
 * each modelDescription.xml by name (FMI 2: q[1], q[2], ...; FMI 3: the
 * array q and its Dimension), so it runs any exported pair of any joint
 * count. The same source is built with gcc (linux64), mingw (win64, run
 * under wine) and the aarch64 cross compiler (run under qemu-user), and the
 * figures it prints are compared.
 *
 * Usage: fmu_master PLATFORM CONTROLLER_DIR PLANT_DIR STOP_TIME
 * PLATFORM is the folder under binaries/ (linux64, win64, x86_64-linux,
 * aarch64-linux, ...).
 * Prints one line: "fmi V joints N band T final_energy E e_ref R" (V the
 * controller's FMI version, T = -1 when the
 * energy never stays in the 5 % band). Exit code 0, or 1 with a message. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"

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

/* Warnings and errors go to stderr. */
static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
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

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message) {
    if (status < fmi3Warning) return;
    fprintf(stderr, "  [%s] %s: %s\n", category, (const char *)env, message);
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

/* The start of the variable `name`'s element (FMI 2: <ScalarVariable
 * name=...; FMI 3: <Float64 name=...), or NULL. */
static const char *variable_element(const char *xml, int version, const char *name) {
    char needle[128];
    snprintf(needle, sizeof needle, "<%s name=\"%s\"",
             version == 3 ? "Float64" : "ScalarVariable", name);
    return strstr(xml, needle);
}

/* The value reference of the variable `name`, or -1. */
static long value_reference(const char *xml, int version, const char *name) {
    const char *p = variable_element(xml, version, name);
    char vr[32];
    if (!p || !attribute(p, "valueReference=\"", vr, sizeof vr)) return -1;
    return strtol(vr, NULL, 10);
}

typedef struct {
    int version; /* 2 or 3, from fmiVersion */
    char identifier[256];
    char token[128];     /* FMI 2 guid, FMI 3 instantiationToken */
    char resources[4096]; /* FMI 2: file: URI; FMI 3: a path ending with '/' */
    char *xml;
    library_t library;
    void *instance;
    /* FMI 2.0 */
    fmi2InstantiateTYPE *instantiate2;
    fmi2SetupExperimentTYPE *setup_experiment2;
    fmi2EnterInitializationModeTYPE *enter_initialization2;
    fmi2ExitInitializationModeTYPE *exit_initialization2;
    fmi2SetRealTYPE *set_real2;
    fmi2GetRealTYPE *get_real2;
    fmi2DoStepTYPE *do_step2;
    fmi2TerminateTYPE *terminate2;
    fmi2FreeInstanceTYPE *free_instance2;
    /* FMI 3.0 */
    fmi3InstantiateCoSimulationTYPE *instantiate3;
    fmi3EnterInitializationModeTYPE *enter_initialization3;
    fmi3ExitInitializationModeTYPE *exit_initialization3;
    fmi3SetFloat64TYPE *set_float64;
    fmi3GetFloat64TYPE *get_float64;
    fmi3DoStepTYPE *do_step3;
    fmi3TerminateTYPE *terminate3;
    fmi3FreeInstanceTYPE *free_instance3;
} Fmu;

/* The resources folder of an unpacked FMU folder (an absolute path; on
 * Windows `C:\dir` becomes `C:/dir`): FMI 2 `file:///dir/resources`, FMI 3
 * `/dir/resources/`. */
static void resource_location(int version, const char *dir, char *out, size_t size) {
    char path[3072];
    snprintf(path, sizeof path, "%s/resources", dir);
    for (char *p = path; *p; p++)
        if (*p == '\\') *p = '/';
    if (version == 3)
        snprintf(out, size, "%s/", path);
    else
        snprintf(out, size, "file://%s%s", path[0] == '/' ? "" : "/", path);
}

#define LOAD(fmu, field, name)                                                     \
    do {                                                                           \
        *(void **)&(fmu)->field = symbol((fmu)->library, name);                    \
        if (!(fmu)->field) fail("%s: no symbol %s", (fmu)->identifier, name);      \
    } while (0)

static void load(Fmu *fmu, const char *platform, const char *dir) {
    char path[4096], version[16];
    snprintf(path, sizeof path, "%s/modelDescription.xml", dir);
    fmu->xml = read_file(path);
    if (!attribute(fmu->xml, "fmiVersion=\"", version, sizeof version))
        fail("%s: no fmiVersion", path);
    fmu->version = version[0] == '3' ? 3 : 2;
    if (!attribute(fmu->xml, "modelIdentifier=\"", fmu->identifier, sizeof fmu->identifier) ||
        !attribute(fmu->xml, fmu->version == 3 ? "instantiationToken=\"" : "guid=\"", fmu->token,
                   sizeof fmu->token))
        fail("%s: no modelIdentifier, or no guid (FMI 2) / instantiationToken (FMI 3)", path);
    snprintf(path, sizeof path, "%s/binaries/%s/%s%s", dir, platform, fmu->identifier,
             LIBRARY_SUFFIX);
    fmu->library = open_library(path);
    if (!fmu->library) fail("cannot load %s", path);
    resource_location(fmu->version, dir, fmu->resources, sizeof fmu->resources);
    if (fmu->version == 3) {
        LOAD(fmu, instantiate3, "fmi3InstantiateCoSimulation");
        LOAD(fmu, enter_initialization3, "fmi3EnterInitializationMode");
        LOAD(fmu, exit_initialization3, "fmi3ExitInitializationMode");
        LOAD(fmu, set_float64, "fmi3SetFloat64");
        LOAD(fmu, get_float64, "fmi3GetFloat64");
        LOAD(fmu, do_step3, "fmi3DoStep");
        LOAD(fmu, terminate3, "fmi3Terminate");
        LOAD(fmu, free_instance3, "fmi3FreeInstance");
    } else {
        LOAD(fmu, instantiate2, "fmi2Instantiate");
        LOAD(fmu, setup_experiment2, "fmi2SetupExperiment");
        LOAD(fmu, enter_initialization2, "fmi2EnterInitializationMode");
        LOAD(fmu, exit_initialization2, "fmi2ExitInitializationMode");
        LOAD(fmu, set_real2, "fmi2SetReal");
        LOAD(fmu, get_real2, "fmi2GetReal");
        LOAD(fmu, do_step2, "fmi2DoStep");
        LOAD(fmu, terminate2, "fmi2Terminate");
        LOAD(fmu, free_instance2, "fmi2FreeInstance");
    }
}

static fmi2CallbackFunctions callbacks2 = {logger2, NULL, NULL, NULL, NULL};

/* fmi2Status and fmi3Status share OK = 0 and Warning = 1. */
static void check(const Fmu *fmu, int status, const char *call) {
    if (status != 0 && status != 1)
        fail("%s: %s returned status %d", fmu->identifier, call, status);
}

/* A Float64 variable of a joint count's values: FMI 2 one scalar per joint
 * (`base[1]`, `base[2]`, ...) or the scalar `base`; FMI 3 one array (or
 * scalar) variable. */
typedef struct {
    const char *name;
    unsigned int vr[MAX_JOINTS];
    size_t nvr;    /* value references */
    size_t values; /* values */
} Variable;

/* The variable `base`; values = 0 when the FMU has none. */
static Variable variable(const Fmu *fmu, const char *base) {
    Variable v = {base, {0}, 0, 0};
    long vr = value_reference(fmu->xml, fmu->version, base);
    if (vr >= 0) {
        v.vr[0] = (unsigned int)vr;
        v.nvr = 1;
        v.values = 1;
        if (fmu->version == 3) {
            /* <Float64 ...>[<Dimension start="N"/>]</Float64> or <Float64 .../> */
            const char *p = variable_element(fmu->xml, 3, base);
            const char *tag_end = strchr(p, '>');
            const char *close = strstr(p, "</Float64>");
            const char *dimension = strstr(p, "<Dimension start=\"");
            char count[32];
            if (tag_end && tag_end[-1] != '/' && close && dimension && dimension < close &&
                attribute(dimension, "<Dimension start=\"", count, sizeof count)) {
                v.values = (size_t)strtoul(count, NULL, 10);
                if (v.values > MAX_JOINTS) fail("%s: %s has more than %d values",
                                                fmu->identifier, base, MAX_JOINTS);
            }
        }
        return v;
    }
    if (fmu->version == 3) return v;
    for (; v.nvr < MAX_JOINTS; v.nvr++) {
        char name[64];
        snprintf(name, sizeof name, "%s[%zu]", base, v.nvr + 1);
        vr = value_reference(fmu->xml, 2, name);
        if (vr < 0) break;
        v.vr[v.nvr] = (unsigned int)vr;
    }
    v.values = v.nvr;
    return v;
}

static Variable required(const Fmu *fmu, const char *base) {
    Variable v = variable(fmu, base);
    if (v.values == 0) fail("%s: no variable %s", fmu->identifier, base);
    return v;
}

static void get(const Fmu *fmu, const Variable *v, double *values) {
    if (fmu->version == 3)
        check(fmu, fmu->get_float64(fmu->instance, v->vr, v->nvr, values, v->values),
              "fmi3GetFloat64");
    else
        check(fmu, fmu->get_real2(fmu->instance, v->vr, v->nvr, values), "fmi2GetReal");
}

static void set(const Fmu *fmu, const Variable *v, const double *values) {
    if (fmu->version == 3)
        check(fmu, fmu->set_float64(fmu->instance, v->vr, v->nvr, values, v->values),
              "fmi3SetFloat64");
    else
        check(fmu, fmu->set_real2(fmu->instance, v->vr, v->nvr, values), "fmi2SetReal");
}

/* Instantiates and enters initialization mode (no stop time: the controller
 * also steps at the last sample). */
static void instantiate(Fmu *f) {
    if (f->version == 3) {
        f->instance = f->instantiate3(f->identifier, f->token, f->resources, fmi3False,
                                      fmi3False, fmi3False, fmi3False, NULL, 0, f->identifier,
                                      logger3, NULL);
        if (!f->instance) fail("%s: fmi3InstantiateCoSimulation failed", f->identifier);
        check(f, f->enter_initialization3(f->instance, fmi3False, 0.0, 0.0, fmi3False, 0.0),
              "fmi3EnterInitializationMode");
    } else {
        f->instance = f->instantiate2(f->identifier, fmi2CoSimulation, f->token, f->resources,
                                      &callbacks2, fmi2False, fmi2False);
        if (!f->instance) fail("%s: fmi2Instantiate failed", f->identifier);
        check(f, f->setup_experiment2(f->instance, fmi2False, 0.0, 0.0, fmi2False, 0.0),
              "fmi2SetupExperiment");
        check(f, f->enter_initialization2(f->instance), "fmi2EnterInitializationMode");
    }
}

static void exit_initialization(const Fmu *f) {
    if (f->version == 3)
        check(f, f->exit_initialization3(f->instance), "fmi3ExitInitializationMode");
    else
        check(f, f->exit_initialization2(f->instance), "fmi2ExitInitializationMode");
}

static void do_step(const Fmu *f, double t, double h) {
    if (f->version == 3) {
        fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
        double last = t;
        check(f, f->do_step3(f->instance, t, h, fmi3True, &event, &terminate, &early, &last),
              "fmi3DoStep");
        if (terminate || early) fail("%s: fmi3DoStep at t = %g asked to stop", f->identifier, t);
    } else {
        check(f, f->do_step2(f->instance, t, h, fmi2True), "fmi2DoStep");
    }
}

static void terminate_and_free(const Fmu *f) {
    if (f->version == 3) {
        check(f, f->terminate3(f->instance), "fmi3Terminate");
        f->free_instance3(f->instance);
    } else {
        check(f, f->terminate2(f->instance), "fmi2Terminate");
        f->free_instance2(f->instance);
    }
}

int main(int argc, char **argv) {
    if (argc != 5) fail("usage: fmu_master PLATFORM CONTROLLER_DIR PLANT_DIR STOP_TIME");
    Fmu controller = {0}, plant = {0};
    load(&controller, argv[1], argv[2]);
    load(&plant, argv[1], argv[3]);
    double stop = atof(argv[4]);

    /* Plant outputs q, qd, energy; inputs tau; parameters q0. Controller
     * inputs q, qd; outputs tau. */
    Variable plant_q = required(&plant, "q"), plant_qd = required(&plant, "qd");
    Variable plant_tau = required(&plant, "tau"), q0 = required(&plant, "q0");
    Variable ctrl_q = required(&controller, "q"), ctrl_qd = required(&controller, "qd");
    Variable ctrl_tau = required(&controller, "tau");
    size_t n = plant_q.values;
    if (plant_qd.values != n || plant_tau.values != n || q0.values != n ||
        ctrl_q.values != n || ctrl_qd.values != n || ctrl_tau.values != n)
        fail("the controller and the plant disagree on the joints");
    Variable energy = required(&plant, "energy"), e_ref_var = required(&controller, "E_ref");

    instantiate(&plant);
    instantiate(&controller);
    double start[MAX_JOINTS];
    for (size_t j = 0; j < n; j++) start[j] = START_ANGLE;
    set(&plant, &q0, start);
    exit_initialization(&plant);
    double q[MAX_JOINTS], qd[MAX_JOINTS], tau[MAX_JOINTS], e, e_ref;
    get(&plant, &plant_q, q);
    get(&plant, &plant_qd, qd);
    /* The first solve, at exit from initialization mode, uses these inputs. */
    set(&controller, &ctrl_q, q);
    set(&controller, &ctrl_qd, qd);
    exit_initialization(&controller);
    get(&controller, &e_ref_var, &e_ref);

    long steps = lround(stop / STEP);
    double band = -1.0;
    int inside = 0;
    for (long k = 0; k <= steps; k++) {
        double t = (double)k * STEP;
        get(&plant, &plant_q, q);
        get(&plant, &plant_qd, qd);
        get(&plant, &energy, &e);
        if (fabs(e - e_ref) >= 0.05 * fabs(e_ref) || !isfinite(e)) {
            inside = 0;
        } else if (!inside) {
            inside = 1;
            band = t;
        }
        if (k > 0) {
            set(&controller, &ctrl_q, q);
            set(&controller, &ctrl_qd, qd);
        }
        do_step(&controller, t, STEP);
        get(&controller, &ctrl_tau, tau);
        if (k == steps) break;
        set(&plant, &plant_tau, tau);
        do_step(&plant, t, STEP);
    }
    terminate_and_free(&plant);
    terminate_and_free(&controller);
    printf("fmi %d joints %zu band %.3f final_energy %.9f e_ref %.6f\n", controller.version, n,
           inside ? band : -1.0, e, e_ref);
    return 0;
}
