# plotbridge: the two commands are `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
WHEELHOUSE := $(VENV)/wheelhouse
HOST ?= 0.0.0.0
PORT ?= 8000
SERIAL ?=
SIM_SPEED ?= 1
BOARD ?= uno-cnc-shield
DATA_DIR ?= data
ARGS ?=
# pytest-xdist workers for `make test` (the board profiles and servers are independent;
# --dist loadfile keeps a file's tests, and its module fixtures, on one worker)
TEST_JOBS ?= $(shell nproc)
BOARDS := $(shell sed -n "s/^BOARDS := //p" firmware/Makefile)

INKSCAPE_EXTENSIONS ?= $(HOME)/.config/inkscape/extensions

.PHONY: run test setup setup-test native firmware boards sim lint flash install-service uninstall-service \
        pi-check bench clean inkscape-extension screenshots

run: setup firmware sim
	$(VENV)/bin/plotbridge serve --host $(HOST) --port $(PORT) --data-dir $(DATA_DIR) \
	  $(if $(SERIAL),--serial $(SERIAL),--virtual --sim-speed $(SIM_SPEED) --board $(BOARD)) $(ARGS)

test: setup-test sim
	$(MAKE) -j$(TEST_JOBS) boards
	$(MAKE) -C firmware test
	$(VENV)/bin/pytest -n $(TEST_JOBS) --dist loadfile

setup: .stamps/system-run $(VENV)/.stamp native
setup-test: .stamps/system-test $(VENV)/.stamp-dev $(WHEELHOUSE)/.stamp native

# The server's C helpers (server/plotbridge/native/), loaded with ctypes.
NATIVE_DIR := server/plotbridge/native
native: $(NATIVE_DIR)/build/libgcodescan.so $(NATIVE_DIR)/build/libmovelines.so $(NATIVE_DIR)/build/libsimplify.so \
        $(NATIVE_DIR)/build/libpreviewjson.so $(NATIVE_DIR)/build/libtextcheck.so \
        $(NATIVE_DIR)/build/libwirebytes.so

$(NATIVE_DIR)/build/lib%.so: $(NATIVE_DIR)/%.c $(NATIVE_DIR)/thousandths.h
	@mkdir -p $(dir $@)
	$(CC) -std=gnu11 -O2 -ffp-contract=off -Wall -Wextra -Werror -fPIC -shared $< -o $@.tmp -lm && mv $@.tmp $@

.stamps/system-%: scripts/setup-system
	scripts/setup-system $*
	@mkdir -p .stamps && touch $@

# The pins as wheels, per architecture: on armhf Debian's numpy and shapely instead, and the
# optional speed-ups without a wheel left out (requirements-nowheel.txt, with the reasons).
$(VENV)/.stamp: requirements.txt requirements-nowheel.txt server/pyproject.toml scripts/setup-venv
	scripts/setup-venv $(PYTHON) $(VENV)
	touch $@

$(VENV)/.stamp-dev: $(VENV)/.stamp requirements-dev.txt requirements-inkex.txt
	$(PY) -m pip install -q --disable-pip-version-check -r requirements-dev.txt
	$(PY) -m pip install -q --disable-pip-version-check --no-deps -r requirements-inkex.txt
	touch $@

# Wheels of the pins, vpype and the build backend, for the packaging test's offline installs
# of ./server into fresh venvs (tests/e2e/test_packaging.py): no download at test time.
$(WHEELHOUSE)/.stamp: $(VENV)/.stamp-dev
	$(PY) -m pip download -q --disable-pip-version-check --only-binary=:all: -d $(WHEELHOUSE) \
	  -c requirements-dev.txt -r requirements.txt vpype setuptools
	touch $@

firmware:
	$(MAKE) -C firmware BOARD=$(BOARD) all

# every board profile's firmware (each builds in its own directory, so in parallel)
boards: $(addprefix board-,$(BOARDS))
board-%:
	$(MAKE) -C firmware BOARD=$* all

sim:
	$(MAKE) -C firmware sim

lint: setup-test
	$(VENV)/bin/ruff check server tests bench

flash: .stamps/system-run firmware
	$(MAKE) -C firmware flash BOARD=$(BOARD) PORT=$(or $(SERIAL),/dev/ttyUSB0)

install-service: setup firmware sim
	scripts/install-service $(CURDIR)

uninstall-service:
	scripts/install-service --uninstall $(CURDIR)

# Debian 12 on arm64 or armhf (a Raspberry Pi) in an emulated root: `make run` there, driven
# from outside (scripts/pi-check, its smoke test on the test fixtures: setup-test). Slow
# (tens of minutes, more on a loaded machine); not part of `make test`.
ARCH ?= arm64
pi-check: setup-test
	scripts/setup-system pi-check
	scripts/pi-check $(ARCH)

inkscape-extension:
	mkdir -p "$(INKSCAPE_EXTENSIONS)"
	cp integrations/inkscape/plotbridge_send.inx integrations/inkscape/plotbridge_send.py "$(INKSCAPE_EXTENSIONS)/"
	@echo "installed into $(INKSCAPE_EXTENSIONS): restart Inkscape, then Extensions > plotbridge > Send to plotter"

bench: setup-test firmware sim
	for b in bench/*.py; do $(PY) $$b || exit 1; done

# every page of the web UI at 1400x900 and 390x844 (a demo server with three virtual
# plotters) into SHOTS_DIR, for review; docs/screenshot.png (the README's) from it
SHOTS_DIR ?= screenshots
screenshots: setup-test sim
	$(MAKE) BOARD=$(BOARD) firmware
	$(PY) scripts/screenshots.py --out $(SHOTS_DIR) --readme

clean:
	$(MAKE) -C firmware clean
	rm -rf .stamps
