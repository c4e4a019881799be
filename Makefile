# Everything sets itself up: a virtual environment, the system library open3d loads
# (libusb-1.0-0), and afford with its dev extras. `make demo`, `make test`, `make bench`.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.afford-installed
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: setup demo test bench imports clean

setup: $(STAMP)

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	@if ! ldconfig -p 2>/dev/null | grep -q 'libusb-1.0.so.0'; then \
		echo "installing libusb-1.0-0 (open3d needs it)"; \
		$(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq libusb-1.0-0 >/dev/null; \
	fi
	$(PY) -m pip install -q --disable-pip-version-check --upgrade pip
	$(PY) -m pip install -q --disable-pip-version-check -e ".[dev]"
	@touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/afford demo

imports: $(STAMP)
	$(VENV)/bin/lint-imports

test: imports
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) benchmarks/explore.py
	$(PY) benchmarks/learn.py
	$(PY) benchmarks/learn.py --scene traverse
	$(PY) benchmarks/plan.py
	$(PY) benchmarks/emulate.py

clean:
	rm -rf $(VENV) demo-out .pytest_cache benchmarks/results
