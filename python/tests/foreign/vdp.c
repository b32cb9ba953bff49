/* A van der Pol oscillator as an FMI 2.0 FMU (Model Exchange and Co-Simulation), written
 * for mbfmu's tests as a "foreign" FMU not built by mbfmu:
 *
 *     x0' = x1,   x1' = mu (1 - x0^2) x1 - x0 + u,   y = x0 + 2 u
 *
 * Value references: 0 x0, 1 x1, 2 der(x0), 3 der(x1), 4 mu, 5 u, 6 y. The outputs x0 and
 * x1 are the states (declared with dependencies="", as Reference-FMUs' VanDerPol does).
 * Compiled with -DWITH_DD it answers fmi2GetDirectionalDerivative exactly; without, it
 * returns fmi2Error there (its model description then says providesDirectionalDerivative
 * is false). Co-Simulation integrates with classic RK4 sub-steps of at most 1e-4 s.
 * Self-contained: the FMI 2.0 types are spelled out instead of including the headers. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;
typedef struct {
    fmi2Boolean newDiscreteStatesNeeded, terminateSimulation, nominalsOfContinuousStatesChanged,
        valuesOfContinuousStatesChanged, nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;
typedef struct {
    void *logger, *allocateMemory, *freeMemory, *stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define EXPORT __attribute__((visibility("default")))

typedef struct {
    double x0, x1, mu, u, t;
} Model;

static void deriv(const Model *m, double x0, double x1, double *d0, double *d1) {
    *d0 = x1;
    *d1 = m->mu * (1 - x0 * x0) * x1 - x0 + m->u;
}

static double value(const Model *m, fmi2ValueReference vr, int *ok) {
    double d0, d1;
    deriv(m, m->x0, m->x1, &d0, &d1);
    *ok = 1;
    switch (vr) {
    case 0: return m->x0;
    case 1: return m->x1;
    case 2: return d0;
    case 3: return d1;
    case 4: return m->mu;
    case 5: return m->u;
    case 6: return m->x0 + 2 * m->u;
    default: *ok = 0; return 0;
    }
}

EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }
EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat;
    return fmi2OK;
}
EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String res,
                                     const fmi2CallbackFunctions *cb, fmi2Boolean vis, fmi2Boolean log) {
    (void)name; (void)type; (void)res; (void)cb; (void)vis; (void)log;
    if (!guid || strcmp(guid, "{vdp-mbfmu-test}") != 0) return NULL;
    Model *m = calloc(1, sizeof(Model));
    if (!m) return NULL;
    m->x0 = 2; m->x1 = 0; m->mu = 1; m->u = 0;
    return m;
}
EXPORT void fmi2FreeInstance(fmi2Component c) { free(c); }
EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean td, fmi2Real tol, fmi2Real t0,
                                      fmi2Boolean sd, fmi2Real t1) {
    (void)td; (void)tol; (void)sd; (void)t1;
    ((Model *)c)->t = t0;
    return fmi2OK;
}
EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
EXPORT fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
EXPORT fmi2Status fmi2Reset(fmi2Component c) {
    Model *m = c;
    m->x0 = 2; m->x1 = 0; m->mu = 1; m->u = 0; m->t = 0;
    return fmi2OK;
}
EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    for (size_t i = 0; i < n; i++) {
        int ok;
        v[i] = value(c, vr[i], &ok);
        if (!ok) return fmi2Error;
    }
    return fmi2OK;
}
EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Model *m = c;
    for (size_t i = 0; i < n; i++) {
        switch (vr[i]) {
        case 0: m->x0 = v[i]; break;
        case 1: m->x1 = v[i]; break;
        case 4: m->mu = v[i]; break;
        case 5: m->u = v[i]; break;
        default: return fmi2Error;
        }
    }
    return fmi2OK;
}
EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) {
    (void)c; (void)s; (void)n; return fmi2Error;
}
EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)c; (void)s; (void)b; (void)n; return fmi2Error;
}
EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) {
    (void)c; (void)b; (void)n; (void)s; return fmi2Error;
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vu[], size_t nu,
                                               const fmi2ValueReference vk[], size_t nk, const fmi2Real dk[],
                                               fmi2Real du[]) {
#ifdef WITH_DD
    const Model *m = c;
    double dx0 = 0, dx1 = 0, duu = 0;
    for (size_t j = 0; j < nk; j++) {
        switch (vk[j]) {
        case 0: dx0 += dk[j]; break;
        case 1: dx1 += dk[j]; break;
        case 5: duu += dk[j]; break;
        default: return fmi2Error;
        }
    }
    for (size_t i = 0; i < nu; i++) {
        switch (vu[i]) {
        case 0: du[i] = dx0; break;
        case 1: du[i] = dx1; break;
        case 2: du[i] = dx1; break;
        case 3: du[i] = (-2 * m->mu * m->x0 * m->x1 - 1) * dx0 + m->mu * (1 - m->x0 * m->x0) * dx1 + duu; break;
        case 6: du[i] = dx0 + 2 * duu; break;
        default: return fmi2Error;
        }
    }
    return fmi2OK;
#else
    (void)c; (void)vu; (void)nu; (void)vk; (void)nk; (void)dk; (void)du;
    return fmi2Error;
#endif
}

/* Model Exchange */
EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }
EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e) {
    (void)c;
    memset(e, 0, sizeof *e);
    return fmi2OK;
}
EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }
EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean nset, fmi2Boolean *ev, fmi2Boolean *term) {
    (void)c; (void)nset;
    *ev = 0; *term = 0;
    return fmi2OK;
}
EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) { ((Model *)c)->t = t; return fmi2OK; }
EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    Model *m = c;
    if (n != 2) return fmi2Error;
    m->x0 = x[0]; m->x1 = x[1];
    return fmi2OK;
}
EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n) {
    if (n != 2) return fmi2Error;
    const Model *m = c;
    deriv(m, m->x0, m->x1, &dx[0], &dx[1]);
    return fmi2OK;
}
EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) {
    (void)c; (void)z; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    if (n != 2) return fmi2Error;
    const Model *m = c;
    x[0] = m->x0; x[1] = m->x1;
    return fmi2OK;
}
EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    (void)c;
    for (size_t i = 0; i < n; i++) x[i] = 1;
    return fmi2OK;
}

/* Co-Simulation */
EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                              const fmi2Integer o[], const fmi2Real v[]) {
    (void)c; (void)vr; (void)o; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                               const fmi2Integer o[], fmi2Real v[]) {
    (void)c; (void)vr; (void)o; (void)v; return n ? fmi2Error : fmi2OK;
}
EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noprior) {
    (void)noprior;
    Model *m = c;
    if (!(h >= 0)) return fmi2Error;
    int k = (int)ceil(h / 1e-4);
    if (k < 1) k = 1;
    double dt = h / k;
    for (int i = 0; i < k; i++) {
        double a0, a1, b0, b1, c0, c1, d0, d1;
        deriv(m, m->x0, m->x1, &a0, &a1);
        deriv(m, m->x0 + dt / 2 * a0, m->x1 + dt / 2 * a1, &b0, &b1);
        deriv(m, m->x0 + dt / 2 * b0, m->x1 + dt / 2 * b1, &c0, &c1);
        deriv(m, m->x0 + dt * c0, m->x1 + dt * c1, &d0, &d1);
        m->x0 += dt / 6 * (a0 + 2 * b0 + 2 * c0 + d0);
        m->x1 += dt / 6 * (a1 + 2 * b1 + 2 * c1 + d1);
    }
    m->t = t + h;
    return fmi2OK;
}
EXPORT fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
EXPORT fmi2Status fmi2GetStatus(fmi2Component c, fmi2StatusKind s, fmi2Status *v) {
    (void)c; (void)s; (void)v; return fmi2Error;
}
EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, fmi2StatusKind s, fmi2Real *v) {
    if (s != fmi2LastSuccessfulTime) return fmi2Error;
    *v = ((Model *)c)->t;
    return fmi2OK;
}
EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, fmi2StatusKind s, fmi2Integer *v) {
    (void)c; (void)s; (void)v; return fmi2Error;
}
EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, fmi2StatusKind s, fmi2Boolean *v) {
    (void)c; (void)s; (void)v; return fmi2Error;
}
EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, fmi2StatusKind s, fmi2String *v) {
    (void)c; (void)s; (void)v; return fmi2Error;
}
