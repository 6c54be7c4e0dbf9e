# Thin wrapper over CMake/ctest. `make run` and `make test` are the README's two commands.
# CUDA is built when nvcc is found (CUDA=ON/OFF forces it). CATALYST=ON builds the ParaView
# Catalyst in-situ adaptor (needs paraview-dev python3-paraview; see README).
BUILD ?= build
JOBS ?= 2
SCENE ?= inputs/dam_break_2d.yaml
OUT ?= out/dam_break_2d
CUDA ?=
CATALYST ?=
PRECISION ?= double
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

export OMPI_ALLOW_RUN_AS_ROOT=1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1

PACKAGES := build-essential cmake ninja-build pkg-config openmpi-bin libopenmpi-dev \
  libpetsc-real-dev libhdf5-openmpi-dev libgtest-dev libgmock-dev libyaml-cpp-dev libcli11-dev

# CATALYST=ON also needs ParaView 5.11 and the -dev packages its CMake config asks for (about
# 1.2 GB; DEPENDENCIES.md). python3-paraview also brings pvpython, which the paraview_xdmf test uses.
PARAVIEW_PACKAGES := paraview-dev python3-paraview libutfcpp-dev liblz4-dev libdouble-conversion-dev \
  libboost-dev libfreetype-dev libglew-dev libxml2-dev libx11-dev libnetcdf-dev
ifeq ($(CATALYST),ON)
PACKAGES += $(PARAVIEW_PACKAGES)
endif

.PHONY: deps configure build run test test-unit check clean

deps:
	@dpkg -s $(PACKAGES) >/dev/null 2>&1 || \
	  ($(SUDO) apt-get update -q && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q $(PACKAGES))

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DSPHDEM_PRECISION=$(PRECISION) $(if $(CUDA),-DSPHDEM_ENABLE_CUDA=$(CUDA)) \
	  $(if $(CATALYST),-DSPHDEM_ENABLE_CATALYST=$(CATALYST))

build: configure
	cmake --build $(BUILD) -j $(JOBS)

run: build
	$(BUILD)/sphdem run $(SCENE) --out $(OUT)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-unit: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -L unit

clean:
	rm -rf $(BUILD)
