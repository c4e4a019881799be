# Everything sets itself up: a virtual environment, the system library open3d loads
# (libusb-1.0-0), and afford with its dev extras. `make demo`, `make test`, `make bench`.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.afford-installed
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: setup demo test bench reproduce imports clean

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

# grimp walks one folder per package: lint a copy nested as the wheel nests it
imports: $(STAMP)
	@rm -rf $(VENV)/lint && mkdir -p $(VENV)/lint
	@cp -r afford_cli $(VENV)/lint/afford && for p in sim features learn plan; do cp -r $$p $(VENV)/lint/afford/$$p; done
	cd $(VENV)/lint && PYTHONPATH=. ../bin/lint-imports --config ../../pyproject.toml

# the tests run on TEST_JOBS processes (pytest-xdist; 2 here: 21-22 minutes instead of 33-35)
TEST_JOBS ?= 2
test: imports
	$(PY) -m pytest -q -n $(TEST_JOBS) --dist worksteal

bench: $(STAMP)
	$(PY) benchmarks/explore.py
	$(PY) benchmarks/learn.py
	$(PY) benchmarks/learn.py --scene traverse
	$(PY) benchmarks/plan.py
	$(PY) benchmarks/emulate.py
	$(PY) benchmarks/curiosity.py

# every thesis figure's script in its quick mode, then reproduce/index.md linking them. A
# chapter's scripts run one after another (they share explorations and models of the same
# recipe through reproduce/.cache, emptied before and after, so nothing from an older
# checkout is ever reused); chapters run in REPRODUCE_LANES lanes side by side (_run.py there)
REPRODUCE_LANES ?= 2
reproduce: $(STAMP)
	@rm -rf reproduce/.cache && mkdir -p reproduce
	@$(PY) examples/reproduce/_run.py --quick --out reproduce --cache reproduce/.cache --lanes $(REPRODUCE_LANES); \
	  status=$$?; rm -rf reproduce/.cache; exit $$status

clean:
	rm -rf $(VENV) demo-out .pytest_cache benchmarks/results reproduce
