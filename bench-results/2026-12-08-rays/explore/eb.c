// Exploration: Embree query variants on the dumped cornell-moving rays, one thread, thread CPU
// time (explore/run.sh). -DE3: Mitsuba's Embree 3 (its symbols are in namespace mitsuba).
#include <dlfcn.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <xmmintrin.h>
#include <pmmintrin.h>

typedef struct __attribute__((aligned(16))) { float ox, oy, oz, tnear, dx, dy, dz, time, tfar; unsigned mask, id, flags; } Ray;
typedef struct __attribute__((aligned(16))) { float nx, ny, nz, u, v; unsigned prim, geom, inst, instprim; } Hit;
typedef struct { Ray ray; Hit hit; } RayHit;
#define P 16
typedef struct __attribute__((aligned(64))) { float ox[P], oy[P], oz[P], tnear[P], dx[P], dy[P], dz[P], time[P], tfar[P]; unsigned mask[P], id[P], flags[P]; } Ray16;
typedef struct __attribute__((aligned(64))) { float nx[P], ny[P], nz[P], u[P], v[P]; unsigned prim[P], geom[P], inst[P], instprim[P]; } Hit16;
typedef struct { Ray16 ray; Hit16 hit; } RayHit16;
typedef struct __attribute__((aligned(32))) { float ox[8], oy[8], oz[8], tnear[8], dx[8], dy[8], dz[8], time[8], tfar[8]; unsigned mask[8], id[8], flags[8]; } Ray8;
typedef struct __attribute__((aligned(16))) { float ox[4], oy[4], oz[4], tnear[4], dx[4], dy[4], dz[4], time[4], tfar[4]; unsigned mask[4], id[4], flags[4]; } Ray4;
typedef struct { int flags; int feature_mask; void *context; void *filter; void *cb; } Args;

static void *(*NewDevice)(const char *);
static void *(*NewScene)(void *);
static void (*SetSceneBuildQuality)(void *, int);
static void (*SetSceneFlags)(void *, int);
static void *(*NewGeometry)(void *, int);
static void *(*SetNewGeometryBuffer)(void *, int, unsigned, int, size_t, size_t);
static void (*SetGeometryBuildQuality)(void *, int);
static void (*CommitGeometry)(void *);
static unsigned (*AttachGeometry)(void *, void *);
static void (*ReleaseGeometry)(void *);
static void (*CommitScene)(void *);
static void (*ReleaseScene)(void *);
#ifdef E3
typedef struct { int flags; void *filter; unsigned inst[1]; } Ctx;
static Ctx ctx3 = {0, 0, {~0u}};
static void (*Occluded1_)(void *, Ctx *, Ray *);
static void (*Intersect1_)(void *, Ctx *, RayHit *);
static void (*Occluded4_)(const int *, void *, Ctx *, Ray4 *);
static void (*Occluded8_)(const int *, void *, Ctx *, Ray8 *);
static void (*Occluded16_)(const int *, void *, Ctx *, Ray16 *);
static void (*Intersect16_)(const int *, void *, Ctx *, RayHit16 *);
#define Occluded1(s, r, a) Occluded1_(s, &ctx3, r)
#define Intersect1(s, r, a) Intersect1_(s, &ctx3, r)
#define Occluded4(v, s, r, a) Occluded4_(v, s, &ctx3, r)
#define Occluded8(v, s, r, a) Occluded8_(v, s, &ctx3, r)
#define Occluded16(v, s, r, a) Occluded16_(v, s, &ctx3, r)
#define Intersect16(v, s, r, a) Intersect16_(v, s, &ctx3, r)
#else
static void (*Occluded1)(void *, Ray *, Args *);
static void (*Intersect1)(void *, RayHit *, Args *);
static void (*Occluded4)(const int *, void *, Ray4 *, Args *);
static void (*Occluded8)(const int *, void *, Ray8 *, Args *);
static void (*Occluded16)(const int *, void *, Ray16 *, Args *);
static void (*Intersect16)(const int *, void *, RayHit16 *, Args *);
#endif

static double cpu(void) { struct timespec t; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }

static float TNEAR = 1.17549435e-38f;
static float *tris; static int ntris;
static float *rays; static long nrays;

static void *build(void *dev, int quality, int groups, int sflags) {
    void *s = NewScene(dev);
    SetSceneBuildQuality(s, quality);
    SetSceneFlags(s, sflags);
    // groups: 1 = one geometry; 2 = as chronolux's flat scene: the static 30 triangles and
    // the moving cube's 12 (the last ones in dump_tris.py's order)
    int b[3]; int nb;
    if (groups == 1) { b[0] = 0; b[1] = ntris; nb = 1; }
    else { b[0] = 0; b[1] = ntris - 12; b[2] = ntris; nb = 2; }
    for (int g = 0; g < nb; g++) {
        int n = b[g + 1] - b[g];
        void *geo = NewGeometry(dev, 0);
        float *v = SetNewGeometryBuffer(geo, 1, 0, 0x9003, 12, 3 * n);
        unsigned *ix = SetNewGeometryBuffer(geo, 0, 0, 0x5003, 12, n);
        memcpy(v, tris + 9 * b[g], 36 * n);
        for (int i = 0; i < 3 * n; i++) ix[i] = i;
        SetGeometryBuildQuality(geo, quality);
        CommitGeometry(geo);
        AttachGeometry(s, geo);
        ReleaseGeometry(geo);
    }
    CommitScene(s);
    return s;
}

static void setray(Ray *r, const float *x) {
    r->ox = x[0]; r->oy = x[1]; r->oz = x[2]; r->dx = x[3]; r->dy = x[4]; r->dz = x[5];
    r->tnear = TNEAR; r->time = 0; r->tfar = 3.4028235e38f; r->mask = ~0u; r->id = 0; r->flags = 0;
}

static long run(void *s, const char *kind, Args *a) {
    long hits = 0;
    if (!strcmp(kind, "o1")) {
        for (long i = 0; i < nrays; i++) { Ray r; setray(&r, rays + 6 * i); Occluded1(s, &r, a); hits += r.tfar < 0; }
    } else if (!strcmp(kind, "i1")) {
        for (long i = 0; i < nrays; i++) {
            RayHit rh; setray(&rh.ray, rays + 6 * i); rh.hit.geom = ~0u; rh.hit.inst = ~0u;
            Intersect1(s, &rh, a); hits += rh.hit.geom != ~0u;
        }
    } else if (!strcmp(kind, "o16")) {
        int valid[P]; for (int k = 0; k < P; k++) valid[k] = -1;
        for (long i = 0; i + P <= nrays; i += P) {
            Ray16 r;
            for (int k = 0; k < P; k++) { const float *x = rays + 6 * (i + k);
                r.ox[k] = x[0]; r.oy[k] = x[1]; r.oz[k] = x[2]; r.dx[k] = x[3]; r.dy[k] = x[4]; r.dz[k] = x[5];
                r.tnear[k] = TNEAR; r.time[k] = 0; r.tfar[k] = 3.4028235e38f; r.mask[k] = ~0u; r.id[k] = 0; r.flags[k] = 0; }
            Occluded16(valid, s, &r, a);
            for (int k = 0; k < P; k++) hits += r.tfar[k] < 0;
        }

    } else if (!strcmp(kind, "o16s") || !strcmp(kind, "i16s")) {
        // rays grouped by direction octant within chunks of CH rays, then packets of 16
        int CH = getenv("CH") ? atoi(getenv("CH")) : 4096;
        int isect = kind[0] == 'i';
        static int idx[1 << 16]; static char occ[1 << 16];
        for (long c0 = 0; c0 < nrays; c0 += CH) {
            int n = nrays - c0 < CH ? nrays - c0 : CH;
            int cnt[9] = {0};
            for (int i = 0; i < n; i++) { const float *x = rays + 6 * (c0 + i); int o = (x[3] < 0) | (x[4] < 0) << 1 | (x[5] < 0) << 2; cnt[o + 1]++; }
            for (int o = 0; o < 8; o++) cnt[o + 1] += cnt[o];
            int pos[8]; for (int o = 0; o < 8; o++) pos[o] = cnt[o];
            for (int i = 0; i < n; i++) { const float *x = rays + 6 * (c0 + i); int o = (x[3] < 0) | (x[4] < 0) << 1 | (x[5] < 0) << 2; idx[pos[o]++] = i; }
            for (int p = 0; p < n; p += P) {
                int m = n - p < P ? n - p : P;
                int valid[P]; for (int k = 0; k < P; k++) valid[k] = k < m ? -1 : 0;
                if (isect) {
                    RayHit16 r;
                    for (int k = 0; k < P; k++) { const float *x = rays + 6 * (c0 + idx[p + (k < m ? k : 0)]);
                        r.ray.ox[k] = x[0]; r.ray.oy[k] = x[1]; r.ray.oz[k] = x[2]; r.ray.dx[k] = x[3]; r.ray.dy[k] = x[4]; r.ray.dz[k] = x[5];
                        r.ray.tnear[k] = TNEAR; r.ray.time[k] = 0; r.ray.tfar[k] = 3.4028235e38f; r.ray.mask[k] = ~0u; r.ray.id[k] = 0; r.ray.flags[k] = 0; r.hit.geom[k] = ~0u; r.hit.inst[k] = ~0u; }
                    Intersect16(valid, s, &r, a);
                    for (int k = 0; k < m; k++) occ[idx[p + k]] = r.hit.geom[k] != ~0u;
                } else {
                    Ray16 r;
                    for (int k = 0; k < P; k++) { const float *x = rays + 6 * (c0 + idx[p + (k < m ? k : 0)]);
                        r.ox[k] = x[0]; r.oy[k] = x[1]; r.oz[k] = x[2]; r.dx[k] = x[3]; r.dy[k] = x[4]; r.dz[k] = x[5];
                        r.tnear[k] = TNEAR; r.time[k] = 0; r.tfar[k] = 3.4028235e38f; r.mask[k] = ~0u; r.id[k] = 0; r.flags[k] = 0; }
                    Occluded16(valid, s, &r, a);
                    for (int k = 0; k < m; k++) occ[idx[p + k]] = r.tfar[k] < 0;
                }
            }
            for (int i = 0; i < n; i++) hits += occ[i];
        }
    } else if (!strcmp(kind, "o8")) {
        int valid[8]; for (int k = 0; k < 8; k++) valid[k] = -1;
        for (long i = 0; i + 8 <= nrays; i += 8) {
            Ray8 r;
            for (int k = 0; k < 8; k++) { const float *x = rays + 6 * (i + k);
                r.ox[k] = x[0]; r.oy[k] = x[1]; r.oz[k] = x[2]; r.dx[k] = x[3]; r.dy[k] = x[4]; r.dz[k] = x[5];
                r.tnear[k] = TNEAR; r.time[k] = 0; r.tfar[k] = 3.4028235e38f; r.mask[k] = ~0u; r.id[k] = 0; r.flags[k] = 0; }
            Occluded8(valid, s, &r, a);
            for (int k = 0; k < 8; k++) hits += r.tfar[k] < 0;
        }
    } else if (!strcmp(kind, "o4")) {
        int valid[4]; for (int k = 0; k < 4; k++) valid[k] = -1;
        for (long i = 0; i + 4 <= nrays; i += 4) {
            Ray4 r;
            for (int k = 0; k < 4; k++) { const float *x = rays + 6 * (i + k);
                r.ox[k] = x[0]; r.oy[k] = x[1]; r.oz[k] = x[2]; r.dx[k] = x[3]; r.dy[k] = x[4]; r.dz[k] = x[5];
                r.tnear[k] = TNEAR; r.time[k] = 0; r.tfar[k] = 3.4028235e38f; r.mask[k] = ~0u; r.id[k] = 0; r.flags[k] = 0; }
            Occluded4(valid, s, &r, a);
            for (int k = 0; k < 4; k++) hits += r.tfar[k] < 0;
        }
    } else if (!strcmp(kind, "i16")) {
        int valid[P]; for (int k = 0; k < P; k++) valid[k] = -1;
        for (long i = 0; i + P <= nrays; i += P) {
            RayHit16 r;
            for (int k = 0; k < P; k++) { const float *x = rays + 6 * (i + k);
                r.ray.ox[k] = x[0]; r.ray.oy[k] = x[1]; r.ray.oz[k] = x[2]; r.ray.dx[k] = x[3]; r.ray.dy[k] = x[4]; r.ray.dz[k] = x[5];
                r.ray.tnear[k] = TNEAR; r.ray.time[k] = 0; r.ray.tfar[k] = 3.4028235e38f; r.ray.mask[k] = ~0u; r.ray.id[k] = 0; r.ray.flags[k] = 0;
                r.hit.geom[k] = ~0u; r.hit.inst[k] = ~0u; }
            Intersect16(valid, s, &r, a);
            for (int k = 0; k < P; k++) hits += r.hit.geom[k] != ~0u;
        }
    }
    return hits;
}

int main(int argc, char **argv) {
    // usage: eb LIB TRIS RAYS DEVCFG QUALITY GROUPS SFLAGS FTZ ARGS(0 null,1 incoh all,2 incoh tri,3 coh tri) KINDS...
    void *lib = dlopen(argv[1], RTLD_NOW);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 1; }
#define S(v, n) *(void **)&v = dlsym(lib, n)
#ifdef E3
#define S(v, n) *(void **)&v = dlsym(lib, n); if (!v) { fprintf(stderr, "no %s\n", n); return 1; }
    S(NewDevice, "_ZN7mitsuba12rtcNewDeviceEPKc"); S(NewScene, "_ZN7mitsuba11rtcNewSceneEPNS_11RTCDeviceTyE");
    S(SetSceneBuildQuality, "_ZN7mitsuba23rtcSetSceneBuildQualityEPNS_10RTCSceneTyENS_15RTCBuildQualityE");
    S(SetSceneFlags, "_ZN7mitsuba16rtcSetSceneFlagsEPNS_10RTCSceneTyENS_13RTCSceneFlagsE");
    S(NewGeometry, "_ZN7mitsuba14rtcNewGeometryEPNS_11RTCDeviceTyENS_15RTCGeometryTypeE");
    S(SetNewGeometryBuffer, "_ZN7mitsuba23rtcSetNewGeometryBufferEPNS_13RTCGeometryTyENS_13RTCBufferTypeEjNS_9RTCFormatEmm");
    S(SetGeometryBuildQuality, "_ZN7mitsuba26rtcSetGeometryBuildQualityEPNS_13RTCGeometryTyENS_15RTCBuildQualityE");
    S(CommitGeometry, "_ZN7mitsuba17rtcCommitGeometryEPNS_13RTCGeometryTyE");
    S(AttachGeometry, "_ZN7mitsuba17rtcAttachGeometryEPNS_10RTCSceneTyEPNS_13RTCGeometryTyE");
    S(ReleaseGeometry, "_ZN7mitsuba18rtcReleaseGeometryEPNS_13RTCGeometryTyE");
    S(CommitScene, "_ZN7mitsuba14rtcCommitSceneEPNS_10RTCSceneTyE");
    S(Occluded1_, "_ZN7mitsuba12rtcOccluded1EPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_6RTCRayE");
    S(Occluded4_, "_ZN7mitsuba12rtcOccluded4EPKiPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_7RTCRay4E");
    S(Occluded8_, "_ZN7mitsuba12rtcOccluded8EPKiPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_7RTCRay8E");
    S(Intersect1_, "_ZN7mitsuba13rtcIntersect1EPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_9RTCRayHitE");
    S(Occluded16_, "_ZN7mitsuba13rtcOccluded16EPKiPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_8RTCRay16E");
    S(Intersect16_, "_ZN7mitsuba14rtcIntersect16EPKiPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_11RTCRayHit16E");
#else
    S(NewDevice, "rtcNewDevice"); S(NewScene, "rtcNewScene"); S(SetSceneBuildQuality, "rtcSetSceneBuildQuality");
    S(SetSceneFlags, "rtcSetSceneFlags"); S(NewGeometry, "rtcNewGeometry"); S(SetNewGeometryBuffer, "rtcSetNewGeometryBuffer");
    S(SetGeometryBuildQuality, "rtcSetGeometryBuildQuality"); S(CommitGeometry, "rtcCommitGeometry");
    S(AttachGeometry, "rtcAttachGeometry"); S(ReleaseGeometry, "rtcReleaseGeometry"); S(CommitScene, "rtcCommitScene");
    S(ReleaseScene, "rtcReleaseScene"); S(Occluded1, "rtcOccluded1"); S(Intersect1, "rtcIntersect1");
    S(Occluded4, "rtcOccluded4"); S(Occluded8, "rtcOccluded8"); S(Occluded16, "rtcOccluded16"); S(Intersect16, "rtcIntersect16");
#endif
    FILE *f = fopen(argv[2], "rb"); fseek(f, 0, SEEK_END); long sz = ftell(f); fseek(f, 0, SEEK_SET);
    tris = malloc(sz); fread(tris, 1, sz, f); fclose(f); ntris = sz / 36;
    f = fopen(argv[3], "rb"); fseek(f, 0, SEEK_END); sz = ftell(f); fseek(f, 0, SEEK_SET);
    rays = malloc(sz); fread(rays, 1, sz, f); fclose(f); nrays = sz / 24;
    if (getenv("TNEAR")) TNEAR = atof(getenv("TNEAR"));
    void *dev = NewDevice(argv[4]);
    int quality = atoi(argv[5]), groups = atoi(argv[6]), sflags = atoi(argv[7]), ftz = atoi(argv[8]), am = atoi(argv[9]);
    if (ftz) { _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON); _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON); }
    double t0 = cpu();
    void *s = build(dev, quality, groups, sflags);
    double tb = cpu() - t0;
    Args args = {am == 3 ? 1 : 0, am >= 2 ? 2 : -1, 0, 0, 0};
    Args *a = am ? &args : NULL;
    for (int k = 10; k < argc; k++) {
        double best = 1e9; long hits = 0;
        for (int rep = 0; rep < 5; rep++) { double t = cpu(); hits = run(s, argv[k], a); t = cpu() - t; if (t < best) best = t; }
        printf("%s q%d g%d sf%d ftz%d args%d %-4s %6.2f Mrays/s (1 thread)  hits %ld  build %.3f ms\n", argv[4], quality, groups, sflags, ftz, am, argv[k], nrays / best / 1e6, hits, tb * 1e3);
    }
    return 0;
}
