# The two entry points of the README. Each sets the machine up first (idempotent).
PY ?= python3
OUT ?= out/pipeline

.PHONY: setup run test
setup:
	@bash tools/setup.sh

run: setup
	staregen pipeline --out $(OUT)

test: setup
	$(PY) -m pytest -q -n 2
