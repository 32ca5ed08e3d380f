# Thin wrapper over CMake. `make demo` runs the main job, `make test` builds and runs every test.
# Both first install the Debian packages the project needs when any is missing (as root).

BUILD_DIR   ?= build
RELEASE_DIR ?= build-release
JOBS        ?= $(shell nproc)
# clang and its runtimes (libclang-rt) build the sanitizer job of `make test` and `make fuzz`;
# libbenchmark-dev the micro-benchmarks (`make microbench`, and a smoke test in `make test`);
# python3-dev, python3-numpy, pybind11-dev and python3-pytest the Python package and its tests;
# libopenmpi-dev and openmpi-bin `sesi sweep` across MPI ranks (its tests run mpirun with 1-3 ranks).
# librandom123-dev the counter-based random numbers of the Langevin thermostat (header-only; the core
# library needs Eigen alone, sesi/thermostat.hpp adds Random123).
# lammps (run as the program `lmp`, never linked) the flat-space peer: tests/lammps compares forces and
# NVE energy traces of periodic Lennard-Jones boxes with it, and `sesi bench --scaling` times it.
# chromium (headless) opens the pages of `sesi view` in tests/view and draws the viewer's figures.
APT_PACKAGES := cmake g++ make libeigen3-dev libboost-dev doctest-dev libtomlplusplus-dev \
                libcli11-dev python3-matplotlib clang libclang-rt-14-dev libbenchmark-dev \
                libhdf5-dev python3-h5py python3-dev python3-numpy pybind11-dev python3-pytest \
                libopenmpi-dev openmpi-bin librandom123-dev lammps chromium

.PHONY: deps configure build test demo clean fuzz figures microbench sweep-example

deps:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing; \
	fi

# Debian's Python (its NumPy, pytest, matplotlib), whatever python3 comes first in PATH.
PYTHON3 := $(shell test -x /usr/bin/python3 && echo /usr/bin/python3 || command -v python3)

# -g1 (line tables and functions, enough for backtraces) instead of -g: a third less compile time
# on the template-heavy test files (tests/core/symplectic.cpp with g++ 12: 31 s against 47 s),
# which keeps a fresh-clone `make test` within CI's time.
# SESI_REQUIRE_ALL_TESTS: deps installed every optional part, so a test that cannot run fails
# configure, and one that skips at run time fails `make test` (tests/check_skips.cmake prints why).
configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSESI_WERROR=ON -DSESI_BUILD_BENCHMARKS=ON \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DPython3_EXECUTABLE=$(PYTHON3) -DSESI_REQUIRE_ALL_TESTS=ON

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS) --output-junit ctest-junit.xml
	cmake -D JUNIT=$(BUILD_DIR)/ctest-junit.xml -P tests/check_skips.cmake

demo: deps
	cmake -S . -B $(RELEASE_DIR) -DCMAKE_BUILD_TYPE=Release -DSESI_BUILD_TESTS=OFF
	cmake --build $(RELEASE_DIR) -j $(JOBS) --target sesi_program
	$(RELEASE_DIR)/src/sesi run --out sesi-out/paper
	@# Debian's python3-matplotlib belongs to /usr/bin/python3, whatever python3 comes first in PATH.
	$$(test -x /usr/bin/python3 && echo /usr/bin/python3 || echo python3) tools/plot_run.py sesi-out/paper

# Google Benchmark micro-benchmarks of a step's pieces, Release build; prints ratios at the end.
microbench: deps
	cmake -S . -B $(RELEASE_DIR) -DCMAKE_BUILD_TYPE=Release -DSESI_BUILD_TESTS=OFF -DSESI_BUILD_BENCHMARKS=ON
	cmake --build $(RELEASE_DIR) -j $(JOBS) --target sesi_microbench
	$(RELEASE_DIR)/bench/sesi_microbench

clean:
	rm -rf $(BUILD_DIR) $(RELEASE_DIR)

# libFuzzer on the scene reader (fuzz/): a clang build in build-fuzz, run for FUZZ_SECONDS with the
# example and bad scenes and the regression inputs (fuzz/regressions) as seeds; the corpus grows in
# fuzz-out/corpus, crashes go to fuzz-out/. Inputs up to 1 MB: the 80 KB deep key of issue #12 lay
# beyond libFuzzer's default limit of 4 KB.
FUZZ_DIR     ?= build-fuzz
FUZZ_SECONDS ?= 600
fuzz: deps
	cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
	  -DSESI_BUILD_FUZZ=ON -DSESI_BUILD_TESTS=OFF -DSESI_BUILD_EXAMPLES=OFF -DSESI_INSTALL=OFF
	cmake --build $(FUZZ_DIR) -j $(JOBS) --target sesi_scene_fuzzer
	mkdir -p fuzz-out/corpus fuzz-out/artifacts
	$(FUZZ_DIR)/fuzz/sesi_scene_fuzzer fuzz-out/corpus examples/scenes tests/program/scene/bad fuzz/regressions \
	  -dict=fuzz/scene.dict -max_len=1048576 -max_total_time=$(FUZZ_SECONDS) -artifact_prefix=fuzz-out/artifacts/ \
	  -print_final_stats=1

# The benchmark figures and tables of docs/benchmarks.md (issue #4): `sesi bench` on the built-in
# scenes in a Release build, the seed's two figures, then the plots (Debian's matplotlib).
BENCH_DIR ?= build-bench
BENCH_OUT ?= sesi-out/bench
figures: deps
	cmake -S . -B $(BENCH_DIR) -DCMAKE_BUILD_TYPE=Release -DSESI_BUILD_TESTS=OFF
	cmake --build $(BENCH_DIR) -j $(JOBS) --target sesi_program
	for s in paper kepler-s2 kepler-h2; do $(BENCH_DIR)/src/sesi bench --scene $$s --out $(BENCH_OUT)/$$s || exit 1; done
	$(BENCH_DIR)/src/sesi bench --figure seed-fig1 --repeats 5 --out $(BENCH_OUT)/figures
	$(BENCH_DIR)/src/sesi bench --figure convergence --out $(BENCH_OUT)/figures
	mkdir -p docs/figures
	$(PYTHON3) tools/figures.py seed-fig1 $(BENCH_OUT)/figures docs/figures/seed-fig1.png
	$(PYTHON3) tools/figures.py convergence $(BENCH_OUT)/figures docs/figures/convergence.png
	$(PYTHON3) tools/plot_bench.py $(BENCH_OUT)/paper $(BENCH_OUT)/kepler-s2 $(BENCH_OUT)/kepler-h2 \
	  --figures docs/figures --markdown | tee $(BENCH_OUT)/report.txt
	@# Long horizons (issue #15): least time to each max energy error level at growing run lengths;
	@# the summary (with issue #15's targets) and the table of docs/benchmarks.md in horizons-report.txt.
	$(BENCH_DIR)/src/sesi bench --scene paper --horizons 800,8000,80000 --out $(BENCH_OUT)/horizons-paper \
	  > $(BENCH_OUT)/horizons-report.txt && cat $(BENCH_OUT)/horizons-report.txt
	$(PYTHON3) tools/plot_horizons.py $(BENCH_OUT)/horizons-paper/horizons.csv \
	  --figure docs/figures/horizons-paper.png --markdown | tee -a $(BENCH_OUT)/horizons-report.txt
	@# Many bodies (issue #11): time per step against N, with the flat references of the same run.
	$(BENCH_DIR)/src/sesi bench --scaling --space sphere --dim 2 --threads 1,2 --out $(BENCH_OUT)/scaling-s2
	$(BENCH_DIR)/src/sesi bench --scaling --space sphere --dim 3 --out $(BENCH_OUT)/scaling-s3
	$(BENCH_DIR)/src/sesi bench --scaling --space hyperbolic --dim 2 --center-distance 0,10 --repeats 5 \
	  --out $(BENCH_OUT)/scaling-h2
	$(BENCH_DIR)/src/sesi bench --scaling --potential cotangent-gravity --methods sesi4 --n 1000,3000,10000 \
	  --out $(BENCH_OUT)/scaling-gravity-s2
	$(PYTHON3) tools/plot_scaling.py $(BENCH_OUT)/scaling-s2 --figure docs/figures/scaling-s2.png --markdown \
	  | tee $(BENCH_OUT)/scaling-report.txt
	$(PYTHON3) tools/plot_scaling.py $(BENCH_OUT)/scaling-s3 $(BENCH_OUT)/scaling-h2 \
	  $(BENCH_OUT)/scaling-gravity-s2 --figure docs/figures/scaling-others.png --markdown | tee -a $(BENCH_OUT)/scaling-report.txt
	@# Matter at a temperature (issue #25): a Lennard-Jones liquid on S^2 quenched by a Langevin
	@# thermostat, g(r) at three temperatures (sesi analyze; docs/observables.md).
	$(PYTHON3) tools/lj_quench.py --sesi $(BENCH_DIR)/src/sesi --out $(BENCH_OUT)/lj-quench \
	  --figure docs/figures/lj-quench-g-r.png | tee $(BENCH_OUT)/lj-quench-report.txt
	@# Topologies (issue #26): the Bolza surface's octagon with the liquid of examples/scenes/bulk-lj-bolza.toml.
	$(PYTHON3) tools/topology_figure.py figure docs/figures/topology-bolza.png --sesi $(BENCH_DIR)/src/sesi --work $(BENCH_OUT)/topology-bolza
	@# The viewer (issue #28): docs/figures/view-*.png, screenshots of `sesi view`'s pages in headless Chromium.
	$(PYTHON3) tools/view_figures.py --sesi $(BENCH_DIR)/src/sesi --work $(BENCH_OUT)/view-figures --out docs/figures
	@# Sweeps (issue #16): the chaos map of docs/sweeps.md.
	$(MAKE) --no-print-directory sweep-example RELEASE_DIR=$(BENCH_DIR)

# The chaos-map example of docs/sweeps.md (issue #16): 1922 runs of examples/sweeps/chaos-map.toml
# (about a minute on two cores), then docs/figures/sweep-chaos-map.png. Some runs fail by design (close
# passes: exit status 3, crossed out in the figure), so the sweep's status 3 is expected.
SWEEP_OUT ?= sesi-out/sweeps/chaos-map
sweep-example: deps
	cmake -S . -B $(RELEASE_DIR) -DCMAKE_BUILD_TYPE=Release -DSESI_BUILD_TESTS=OFF
	cmake --build $(RELEASE_DIR) -j $(JOBS) --target sesi_program
	status=0; $(RELEASE_DIR)/src/sesi sweep examples/sweeps/chaos-map.toml --out $(SWEEP_OUT) --quiet || status=$$?; \
	  test $$status -eq 0 -o $$status -eq 3
	mkdir -p docs/figures
	$(PYTHON3) tools/plot_sweep.py $(SWEEP_OUT) --out docs/figures/sweep-chaos-map.png \
	  --title "chaos map on S^2: examples/sweeps/chaos-map.toml"
