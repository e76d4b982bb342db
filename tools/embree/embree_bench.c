/* Times Embree 3 on the mesh and rays that `neumann bench --export DIR` writes, the way
 * `neumann bench` times neumann: BVH build (HIGH and MEDIUM quality, one thread), then
 * incoherent closest-hit (rtcIntersect1) and shadow (rtcOccluded1) rays with one thread and
 * with all threads, each the best of three passes after a warm-up; then the same rays as packets
 * of 8 and 16 consecutive rays (rtcIntersect8/16, rtcOccluded8/16: the kernels Mitsuba 3's LLVM
 * backend calls, one packet per SIMD register of paths), their SoA copy-in timed with them.
 *
 * Build: cc -O2 -o embree_bench embree_bench.c -lembree3 -lpthread
 * Usage: embree_bench DIR [THREADS]        (a yardstick only: neumann does not link Embree) */
#include <embree3/rtcore.h>
#include <stdbool.h>
#include <sys/types.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void *read_file(const char *dir, const char *name, size_t *len) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "rb");
    if (!f) { fprintf(stderr, "embree_bench: cannot open %s\n", path); exit(1); }
    fseek(f, 0, SEEK_END);
    *len = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    void *data = malloc(*len);
    if (!data || fread(data, 1, *len, f) != *len) { fprintf(stderr, "embree_bench: cannot read %s\n", path); exit(1); }
    fclose(f);
    return data;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static uint32_t nv, nt, nr;
static int64_t mem_now, mem_peak;

/* Embree's memory monitor: bytes allocated (positive) and freed (negative) by the device. */
static bool monitor(void *user, ssize_t bytes, bool post) {
    (void)user; (void)post;
    mem_now += bytes;
    if (mem_now > mem_peak) mem_peak = mem_now;
    return true;
}
static const float *verts, *rays;
static const uint32_t *tris;

static RTCScene build(RTCDevice device, enum RTCBuildQuality quality) {
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, quality);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, quality);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, nv);
    memcpy(v, verts, 12 * (size_t)nv);
    uint32_t *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, nt);
    memcpy(t, tris, 12 * (size_t)nt);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    return scene;
}

struct job { RTCScene scene; int shadow, width; uint32_t begin, end; uint64_t hits; };

/* Packets of `width` (8 or 16) consecutive rays, copied into the packet's structure of arrays
 * (timed with the query); a last partial packet has its other lanes off. */
#define TRACE_PACKETS(N)                                                                          \
    static void trace_packets##N(struct job *j) {                                                \
        struct RTCIntersectContext ctx;                                                          \
        rtcInitIntersectContext(&ctx);                                                           \
        uint64_t hits = 0;                                                                       \
        for (uint32_t i = j->begin; i < j->end; i += N) {                                        \
            __attribute__((aligned(64))) int valid[N];                                           \
            struct RTCRayHit##N rh;                                                              \
            for (int k = 0; k < N; k++) {                                                        \
                valid[k] = i + k < j->end ? -1 : 0;                                              \
                const float *r = rays + 6 * (size_t)(valid[k] ? i + k : i);                      \
                rh.ray.org_x[k] = r[0]; rh.ray.org_y[k] = r[1]; rh.ray.org_z[k] = r[2];         \
                rh.ray.dir_x[k] = r[3]; rh.ray.dir_y[k] = r[4]; rh.ray.dir_z[k] = r[5];         \
                rh.ray.tnear[k] = 0.0f; rh.ray.tfar[k] = INFINITY; rh.ray.time[k] = 0.0f;        \
                rh.ray.mask[k] = 0xFFFFFFFFu; rh.ray.id[k] = 0; rh.ray.flags[k] = 0;             \
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                                      \
                rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;                                   \
            }                                                                                    \
            if (j->shadow) rtcOccluded##N(valid, j->scene, &ctx, &rh.ray);                        \
            else rtcIntersect##N(valid, j->scene, &ctx, &rh);                                     \
            for (int k = 0; k < N; k++)                                                          \
                if (valid[k])                                                                    \
                    hits += j->shadow ? rh.ray.tfar[k] < 0.0f : rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID; \
        }                                                                                        \
        j->hits = hits;                                                                          \
    }
TRACE_PACKETS(8)
TRACE_PACKETS(16)

static void *trace(void *arg) {
    struct job *j = arg;
    if (j->width == 8) { trace_packets8(j); return NULL; }
    if (j->width == 16) { trace_packets16(j); return NULL; }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    uint64_t hits = 0;
    for (uint32_t i = j->begin; i < j->end; i++) {
        const float *r = rays + 6 * (size_t)i;
        struct RTCRayHit rh;
        rh.ray.org_x = r[0]; rh.ray.org_y = r[1]; rh.ray.org_z = r[2];
        rh.ray.dir_x = r[3]; rh.ray.dir_y = r[4]; rh.ray.dir_z = r[5];
        rh.ray.tnear = 0.0f; rh.ray.tfar = INFINITY; rh.ray.time = 0.0f;
        rh.ray.mask = 0xFFFFFFFFu; rh.ray.id = 0; rh.ray.flags = 0;
        if (j->shadow) {
            rtcOccluded1(j->scene, &ctx, &rh.ray);
            hits += rh.ray.tfar < 0.0f;
        } else {
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(j->scene, &ctx, &rh);
            hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
    }
    j->hits = hits;
    return NULL;
}

/* Mrays/s of one pass over all rays on `threads` threads; the hit count through `hits`. */
static double pass(RTCScene scene, int shadow, int width, int threads, uint64_t *hits) {
    pthread_t tid[256];
    struct job jobs[256];
    double t0 = now();
    for (int k = 0; k < threads; k++) {
        jobs[k] = (struct job){scene, shadow, width, (uint32_t)((uint64_t)nr * k / threads),
                               (uint32_t)((uint64_t)nr * (k + 1) / threads), 0};
        pthread_create(&tid[k], NULL, trace, &jobs[k]);
    }
    *hits = 0;
    for (int k = 0; k < threads; k++) { pthread_join(tid[k], NULL); *hits += jobs[k].hits; }
    return nr / (now() - t0) / 1e6;
}

static double best(RTCScene scene, int shadow, int width, int threads, uint64_t *hits) {
    double b = 0.0;
    pass(scene, shadow, width, threads, hits);
    for (int i = 0; i < 3; i++) { double r = pass(scene, shadow, width, threads, hits); if (r > b) b = r; }
    return b;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: embree_bench DIR [THREADS]\n"); return 2; }
    int threads = argc > 2 ? atoi(argv[2]) : 2;
    if (threads < 1 || threads > 256) { fprintf(stderr, "embree_bench: THREADS must be 1..256\n"); return 2; }
    size_t len;
    const uint32_t *mesh = read_file(argv[1], "mesh.bin", &len);
    nv = mesh[0]; nt = mesh[1];
    if (len != 8 + 12 * (size_t)nv + 12 * (size_t)nt) { fprintf(stderr, "embree_bench: mesh.bin has the wrong size\n"); return 1; }
    verts = (const float *)(mesh + 2);
    tris = mesh + 2 + 3 * (size_t)nv;
    const uint32_t *rf = read_file(argv[1], "rays.bin", &len);
    nr = rf[0];
    if (len != 4 + 24 * (size_t)nr) { fprintf(stderr, "embree_bench: rays.bin has the wrong size\n"); return 1; }
    rays = (const float *)(rf + 1);
    printf("Embree %d.%d.%d: %u triangles, %u rays\n", RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, nt, nr);

    RTCDevice one = rtcNewDevice("threads=1");
    RTCScene scene = NULL;
    const char *names[] = {"MEDIUM", "HIGH"};
    enum RTCBuildQuality qualities[] = {RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH};
    rtcSetDeviceMemoryMonitorFunction(one, monitor, NULL);
    for (int q = 0; q < 2; q++) {
        if (scene) rtcReleaseScene(scene);
        mem_now = mem_peak = 0;
        double t0 = now();
        scene = build(one, qualities[q]);
        printf("BVH build (%s quality, 1 thread): %.3f s; %.0f bytes per triangle (%.0f at the peak of the build)\n",
               names[q], now() - t0, (double)mem_now / nt, (double)mem_peak / nt);
    }
    /* Traced on the HIGH-quality BVH (the best Embree can do for rendering). */
    printf("%-36s %12s %12s   hit rate\n", "rays (Mrays/s)", "1 thread", threads == 1 ? "" : "all threads");
    const int widths[] = {1, 8, 16};
    const char *suffix[] = {"", " packets of 8", " packets of 16"};
    for (int wi = 0; wi < 3; wi++) {
        int width = widths[wi];
        for (int shadow = 0; shadow < 2; shadow++) {
            uint64_t hits;
            double r1 = best(scene, shadow, width, 1, &hits);
            double rn = threads > 1 ? best(scene, shadow, width, threads, &hits) : r1;
            char label[64];
            snprintf(label, sizeof label, "%s%s", shadow ? "incoherent shadow" : "incoherent closest-hit", suffix[wi]);
            printf("%-36s %12.2f %12.2f   %.0f %%\n", label, r1, rn, 100.0 * hits / nr);
        }
    }
    rtcReleaseScene(scene);
    rtcReleaseDevice(one);
    return 0;
}
