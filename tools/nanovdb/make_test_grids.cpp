// Writes the NanoVDB test files of neumann's `nanovdb` volume (tests/data/nanovdb/) with
// NanoVDB's own builder and writer, and reference values read back through NanoVDB's own
// trilinear sampler, so that neumann's reader is checked against the library, not itself.
//
//   apt-get install libnanovdb-dev zlib1g-dev
//   g++ -O2 -std=c++17 -DNANOVDB_USE_ZIP tools/nanovdb/make_test_grids.cpp -o /tmp/make_test_grids -lz -lpthread
//   /tmp/make_test_grids tests/data/nanovdb scenes/assets
//
// blob.nvdb (ZIP codec): a fog-volume "density" grid (a lumpy ball straddling index 0 on every
// axis, so it spans eight root tiles, with a rotated, scaled and translated index-to-world map)
// and a "temperature" grid of another voxel size and origin. blob_ref.txt: for 600 world points
// in and around the ball, the density and temperature NanoVDB's SampleFromVoxels<…, 1, false>
// returns at worldToIndexF(p) (pbrt-v4's NanoVDBMedium lookups), and the grids' index and world
// bounding boxes.
//
// voxels.nvdb: three voxels in one leaf, the fuzzing seed (fuzz/run.sh expands it).
//
// fireball.nvdb (second directory; scenes/pbrt_nanovdb.pbrt): a 48³ lumpy ball of smoke,
// "density" 0–1, whose "temperature" (0–30, hottest inside) pbrt's temperaturescale turns into
// kelvin; values in steps of 1/64 so that ZIP compresses them.
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/SampleFromVoxels.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

int main(int argc, char **argv) {
    const std::string dir = argc > 1 ? argv[1] : ".";
    // Density: a ball of radius 12 voxels around index (-2, 3, 1), lumpy, zero outside.
    nanovdb::GridBuilder<float> density(0.0f, nanovdb::GridClass::FogVolume);
    density([](const nanovdb::Coord &ijk) {
        const double x = ijk[0] + 2.0, y = ijk[1] - 3.0, z = ijk[2] - 1.0;
        const double r2 = (x * x + y * y + z * z) / (12.0 * 12.0);
        if (r2 >= 1.0) return 0.0f;
        return float((1.0 - r2) * (1.2 + 0.8 * std::sin(0.37 * x + 0.21 * y) * std::cos(0.29 * z)));
    }, nanovdb::CoordBBox(nanovdb::Coord(-16), nanovdb::Coord(16)));
    // Index to world: rotate 30° about z, then 20° about x, scale by 0.05 (0.08 along y), move.
    const double a = 30.0 * M_PI / 180.0, b = 20.0 * M_PI / 180.0;
    const double rz[3][3] = {{std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1}};
    const double rx[3][3] = {{1, 0, 0}, {0, std::cos(b), -std::sin(b)}, {0, std::sin(b), std::cos(b)}};
    const double s[3] = {0.05, 0.08, 0.05};
    double m[3][3], inv[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double v = 0;
            for (int k = 0; k < 3; ++k) v += rx[i][k] * rz[k][j];
            m[i][j] = v * s[j];  // world = Rx Rz S ijk
        }
    // The inverse: S⁻¹ (Rx Rz)ᵀ.
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) inv[i][j] = m[j][i] / (s[i] * s[i]);
    // Map::set takes transposed (row-vector) matrices.
    double mt[3][3], it[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            mt[i][j] = m[j][i];
            it[i][j] = inv[j][i];
        }
    nanovdb::Map map;
    map.set(mt, it, nanovdb::Vec3d(0.3, -0.2, 0.1), 1.0);
    auto dh = density.getHandle(map, "density");

    // Temperature: 300–2300 "units" falling off from the ball's centre, voxel size 0.07.
    nanovdb::GridBuilder<float> temperature(0.0f, nanovdb::GridClass::FogVolume);
    temperature([](const nanovdb::Coord &ijk) {
        const double r = std::sqrt(double(ijk[0] * ijk[0] + ijk[1] * ijk[1] + ijk[2] * ijk[2])) / 9.0;
        if (r >= 1.0) return 0.0f;
        return float(3.0 + 20.0 * (1.0 - r) * (1.0 - r));
    }, nanovdb::CoordBBox(nanovdb::Coord(-16), nanovdb::Coord(16)));
    auto th = temperature.getHandle(0.07, nanovdb::Vec3d(0.25, -0.1, 0.2), "temperature");

    std::vector<nanovdb::GridHandle<>> handles;
    handles.push_back(std::move(dh));
    handles.push_back(std::move(th));
    nanovdb::io::writeGrids(dir + "/blob.nvdb", handles, nanovdb::io::Codec::ZIP);

    auto d = nanovdb::io::readGrid(dir + "/blob.nvdb", "density");
    auto t = nanovdb::io::readGrid(dir + "/blob.nvdb", "temperature");
    const auto *dg = d.grid<float>();
    const auto *tg = t.grid<float>();
    FILE *f = std::fopen((dir + "/blob_ref.txt").c_str(), "w");
    std::fprintf(f, "# NanoVDB %s: x y z density temperature (SampleFromVoxels order 1 at worldToIndexF)\n",
                 nanovdb::Version().c_str());
    for (const auto *g : {dg, tg}) {
        const auto ib = g->indexBBox();
        const auto wb = g->worldBBox();
        std::fprintf(f, "# %s index %d %d %d %d %d %d world %.9g %.9g %.9g %.9g %.9g %.9g voxels %llu\n",
                     g->gridName(), ib.min()[0], ib.min()[1], ib.min()[2], ib.max()[0], ib.max()[1],
                     ib.max()[2], wb.min()[0], wb.min()[1], wb.min()[2], wb.max()[0], wb.max()[1],
                     wb.max()[2], (unsigned long long)g->activeVoxelCount());
    }
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.9f, 1.1f);
    using Sampler = nanovdb::SampleFromVoxels<nanovdb::FloatGrid::TreeType, 1, false>;
    for (int n = 0; n < 600; ++n) {
        nanovdb::Vec3f p(u(rng), u(rng), u(rng));
        const float dv = Sampler(dg->tree())(dg->worldToIndexF(p));
        const float tv = Sampler(tg->tree())(tg->worldToIndexF(p));
        std::fprintf(f, "%.9g %.9g %.9g %.9g %.9g\n", p[0], p[1], p[2], dv, tv);
    }
    std::fclose(f);

    // voxels.nvdb: three voxels in one leaf (one root tile, one node of each kind), the fuzzing
    // seed that tools/nanovdb/uncompress.py expands to its uncompressed form.
    nanovdb::GridBuilder<float> few(0.0f, nanovdb::GridClass::FogVolume);
    auto acc = few.getAccessor();
    acc.setValue(nanovdb::Coord(1, 2, 3), 0.5f);
    acc.setValue(nanovdb::Coord(2, 2, 3), 1.5f);
    acc.setValue(nanovdb::Coord(1, 3, 4), 2.0f);
    nanovdb::io::writeGrid(dir + "/voxels.nvdb", few.getHandle(0.5, nanovdb::Vec3d(0.0), "density"), nanovdb::io::Codec::ZIP);

    if (argc > 2) {
        const std::string assets = argv[2];
        auto lumps = [](double x, double y, double z) {
            return 0.55 * std::sin(0.45 * x + 0.3 * z) * std::cos(0.38 * y - 0.2 * x) +
                   0.35 * std::sin(0.9 * y + 0.7 * z + 1.3) * std::sin(0.8 * x - 0.5);
        };
        auto q = [](double v) { return float(std::round(v * 64.0) / 64.0); };
        nanovdb::GridBuilder<float> smoke(0.0f, nanovdb::GridClass::FogVolume);
        smoke([&](const nanovdb::Coord &ijk) {
            const double x = ijk[0], y = ijk[1], z = ijk[2];
            const double r = std::sqrt(x * x + y * y + z * z) / (20.0 + 3.0 * lumps(x, y, z));
            return r >= 1.0 ? 0.0f : q(std::min(1.0, 1.6 * (1.0 - r)));
        }, nanovdb::CoordBBox(nanovdb::Coord(-24), nanovdb::Coord(24)));
        nanovdb::GridBuilder<float> heat(0.0f, nanovdb::GridClass::FogVolume);
        heat([&](const nanovdb::Coord &ijk) {
            const double x = ijk[0], y = ijk[1], z = ijk[2];
            const double r = std::sqrt(x * x + y * y + z * z) / (14.0 + 4.0 * lumps(y, z, x));
            return r >= 1.0 ? 0.0f : q(30.0 * (1.0 - r * r));
        }, nanovdb::CoordBBox(nanovdb::Coord(-20), nanovdb::Coord(20)));
        std::vector<nanovdb::GridHandle<>> ball;
        ball.push_back(smoke.getHandle(1.0 / 24.0, nanovdb::Vec3d(0.0), "density"));
        ball.push_back(heat.getHandle(1.0 / 24.0, nanovdb::Vec3d(0.0), "temperature"));
        nanovdb::io::writeGrids(assets + "/fireball.nvdb", ball, nanovdb::io::Codec::ZIP);
    }
    return 0;
}
