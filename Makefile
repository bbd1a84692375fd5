# The two commands: `make demo` sets up and runs the main job, `make test` sets up and runs
# the tests. Both work on a fresh machine with only Python 3.11 (see scripts/setup.sh).
.PHONY: setup demo test test-hands bench lint

setup:
	bash scripts/setup.sh

demo: setup
	MUJOCO_GL=$${MUJOCO_GL:-egl} .venv/bin/rnnpb demo $(ARGS)

# Two workers, each given whole test files (a file's shared fixtures are made once), the
# longest first (tests/conftest.py, STARTED_FIRST); then the pose model's tests in an environment
# of their own (.venv-hands, below), where they must run: a missing model fails them.
test:
	WITH_BROWSER=1 WITH_HANDS=1 bash scripts/setup.sh
	MUJOCO_GL=$${MUJOCO_GL:-egl} MPLBACKEND=Agg .venv/bin/python -m pytest -n 2 --dist loadfile \
		--no-loadscope-reorder --ignore=$(POSE_MODEL_TESTS) $(ARGS)
	$(RUN_POSE_MODEL_TESTS)

# The pose tracker's tests with its model, in .venv-hands: the extra rnnpb[hands] brings
# protobuf < 5 and OpenCV's desktop build, which .venv should not get (docs/perception.md).
# RNNPB_POSE_TESTS=required turns what they would skip for (no model, no photograph, no filmed
# person) into a failure.
POSE_MODEL_TESTS = tests/perception/test_pose_model.py
RUN_POSE_MODEL_TESTS = MUJOCO_GL=$${MUJOCO_GL:-egl} MPLBACKEND=Agg RNNPB_POSE_TESTS=required \
	.venv-hands/bin/python -m pytest -q $(POSE_MODEL_TESTS)

test-hands:
	WITH_HANDS=1 bash scripts/setup.sh
	$(RUN_POSE_MODEL_TESTS) $(ARGS)

bench: setup
	.venv/bin/rnnpb bench

# The type checker reads pyproject.toml's [tool.basedpyright]; --pythonpath points it at the
# project's environment, where the dependencies' types are.
lint: setup
	.venv/bin/ruff check src tests benchmarks tools
	.venv/bin/ruff format --check src tests benchmarks tools
	.venv/bin/basedpyright --project pyproject.toml --pythonpath .venv/bin/python
