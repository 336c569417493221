// A timing driver for one of UTK's samplers (utk-team/utk), built by
// scripts/build-utk-peers.sh with -DUTK_PEER_<NAME>; clsamp's benchmarks/bench_utk.py runs it.
//
//     utk_<name> N D SEED OUT [ITERATIONS [BATCH]]
//
// (SOT: ITERATIONS batches of BATCH directions; PeriodicBNOT (and PERIODIC_BNOT_UNIFORM,
// UTK's code from a uniform start, below): ITERATIONS outer iterations
// of at most BATCH Newton steps each; Faure, Niederreiter: neither.)
//
// calls the sampler's generateSamples(points, N) once and writes OUT: three float64 (the
// seconds generateSamples took by std::chrono::steady_clock, the points' count, their
// dimension) and then the points, row-major float64, little-endian as the host. The time
// covers generateSamples alone: no process start, no file I/O. Anything the sampler prints
// goes to stdout, which the benchmark discards.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <utk/utils/Pointset.hpp>

#if defined(UTK_PEER_SOT)
#include <utk/samplers/SamplerSOT.hpp>
#elif defined(UTK_PEER_PERIODIC_BNOT) || defined(UTK_PEER_PERIODIC_BNOT_UNIFORM)
#include <utk/samplers/SamplerPeriodicBNOT.hpp>
#elif defined(UTK_PEER_FAURE)
#include <utk/samplers/SamplerFaure.hpp>
#elif defined(UTK_PEER_NIEDERREITER)
#include <utk/samplers/SamplerNiederreiter.hpp>
#else
#error "define one of UTK_PEER_SOT, UTK_PEER_PERIODIC_BNOT, UTK_PEER_PERIODIC_BNOT_UNIFORM, UTK_PEER_FAURE, UTK_PEER_NIEDERREITER"
#endif

#if defined(UTK_PEER_PERIODIC_BNOT_UNIFORM)
// UTK's SamplerPeriodicBNOT::generateSamples with one change: the start is uniform in the
// unit torus, where UTK draws it in [0, 0.1)^2 (a cluster that its 20 outer iterations
// do not spread: rho 0.23 at n = 1024). Same PBNOT::Scene calls, same PCG32, same defaults.
struct UniformStartBNOT
{
    utk::PCG32 gen;
    uint32_t its = 20, nits = 20;
    double epsilon = 0.2;

    void setRandomSeed(uint64_t seed) { gen.seed(seed); }
    void setIterations(uint32_t i) { its = i; }
    void setNewtonIterations(uint32_t i) { nits = i; }

    bool generateSamples(utk::Pointset<double>& arg_pts, uint32_t N)
    {
        std::uniform_real_distribution<double> unif(0.0, 1.0);
        PBNOT::Scene bnot_scene;
        std::vector<PBNOT::Point> points;
        std::vector<PBNOT::FT> weights(N, 0.0);
        std::vector<PBNOT::FT> noise(N, 0.0);
        points.reserve(N);
        for (uint32_t i = 0; i < N; i++)
            points.push_back(PBNOT::Point(unif(gen), unif(gen)));
        bnot_scene.construct_triangulation(points, weights, noise);
        bnot_scene.optimize_all(0.0, 0.0, its, epsilon, nits, std::cout, true);
        std::vector<PBNOT::Point> outPoints;
        bnot_scene.collect_visible_points(outPoints);
        arg_pts.Resize(outPoints.size(), 2);
        for (uint32_t i = 0; i < outPoints.size(); i++)
        {
            arg_pts[i][0] = outPoints[i].x();
            arg_pts[i][1] = outPoints[i].y();
        }
        return true;
    }
};
#endif

int main(int argc, char** argv)
{
    if (argc < 5)
    {
        std::fprintf(stderr, "usage: %s N D SEED OUT [ITERATIONS [BATCH]]\n", argv[0]);
        return 2;
    }
    const uint32_t n = std::strtoul(argv[1], nullptr, 10);
    const uint32_t d = std::strtoul(argv[2], nullptr, 10);
    const uint64_t seed = std::strtoull(argv[3], nullptr, 10);
    const char* out = argv[4];
    const long iterations = argc > 5 ? std::strtol(argv[5], nullptr, 10) : -1;
    const long batch = argc > 6 ? std::strtol(argv[6], nullptr, 10) : -1;
    if (n == 0 || d == 0)
    {
        std::fprintf(stderr, "N and D must be positive\n");
        return 2;
    }

#if defined(UTK_PEER_SOT)
    utk::SamplerSOT sampler(d);          // UTK's defaults: 4096 iterations, batches of 64
    sampler.setRandomSeed(seed);
    if (iterations > 0) sampler.setIterations(iterations);
    if (batch > 0) sampler.setBatchSize(batch);
#elif defined(UTK_PEER_PERIODIC_BNOT) || defined(UTK_PEER_PERIODIC_BNOT_UNIFORM)
    if (d != 2)
    {
        std::fprintf(stderr, "PeriodicBNOT is 2-D\n");
        return 2;
    }
    // UTK's defaults: 20 outer iterations (optimize_all's max_iters, which UTK's
    // setNewtonIterations sets), at most 20 Newton steps on the weights in each (its
    // max_newton_iters, set by UTK's setIterations), epsilon 0.2. ITERATIONS here is the
    // outer count, BATCH the Newton steps.
#if defined(UTK_PEER_PERIODIC_BNOT)
    utk::SamplerPeriodicBNOT sampler;
#else
    UniformStartBNOT sampler;
#endif
    sampler.setRandomSeed(seed);
    if (iterations > 0) sampler.setNewtonIterations(iterations);
    if (batch > 0) sampler.setIterations(batch);
#elif defined(UTK_PEER_FAURE)
    utk::SamplerFaure sampler(d);        // deterministic: no seed
    (void)seed; (void)iterations; (void)batch;
#else
    utk::SamplerNiederreiter sampler(d); // base 2, deterministic
    (void)seed; (void)iterations; (void)batch;
#endif

    utk::Pointset<double> points;
    const auto t0 = std::chrono::steady_clock::now();
    const bool ok = sampler.generateSamples(points, n);
    const auto t1 = std::chrono::steady_clock::now();
    if (!ok)
    {
        std::fprintf(stderr, "generateSamples failed\n");
        return 1;
    }
    const double header[3] = {std::chrono::duration<double>(t1 - t0).count(),
                              double(points.Npts()), double(points.Ndim())};
    std::FILE* f = std::fopen(out, "wb");
    if (!f)
    {
        std::perror(out);
        return 1;
    }
    std::fwrite(header, sizeof(double), 3, f);
    std::fwrite(points.Data(), sizeof(double), size_t(points.Npts()) * points.Ndim(), f);
    std::fclose(f);
    return 0;
}
