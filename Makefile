# Thin wrapper over CMake. `make demo` runs the main job, `make test` builds and runs every test.
# Both first install the Debian packages the project needs when any is missing (as root).

BUILD_DIR   ?= build
RELEASE_DIR ?= build-release
JOBS        ?= $(shell nproc)
APT_PACKAGES := cmake g++ make libeigen3-dev libboost-dev doctest-dev libtomlplusplus-dev \
                libcli11-dev python3-matplotlib

.PHONY: deps configure build test demo clean

deps:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing; \
	fi

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSESI_WERROR=ON

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

demo: deps
	cmake -S . -B $(RELEASE_DIR) -DCMAKE_BUILD_TYPE=Release -DSESI_BUILD_TESTS=OFF
	cmake --build $(RELEASE_DIR) -j $(JOBS) --target sesi_program
	$(RELEASE_DIR)/src/sesi run --out sesi-out/paper
	@# Debian's python3-matplotlib belongs to /usr/bin/python3, whatever python3 comes first in PATH.
	$$(test -x /usr/bin/python3 && echo /usr/bin/python3 || echo python3) tools/plot_run.py sesi-out/paper

clean:
	rm -rf $(BUILD_DIR) $(RELEASE_DIR)
