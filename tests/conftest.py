import math
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

# the verification registry (tests/verification.py) is imported by name by the tests
if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
import verification  # noqa: E402
from s3_server import S3Server  # noqa: E402
import slurm  # noqa: E402

DOC = Path(__file__).resolve().parent.parent / "docs" / "studies" / "verification.md"

# ----------------------------------------------------------------------------- slow tests
#: The tests marked ``slow`` (the marker is registered in pyproject.toml): a test file, or a
#: test of a file with all its parametrizations ("file::test"). Each took more than about
#: 5 s in a measured run of the suite; `python3 bootstrap.py test -n 2 -m "not slow"` leaves
#: them out (docs/developer/developer.md, "Running the tests"). tests/test_slow_marker.py
#: fails when an entry names no test.
SLOW = frozenset({
    "tests/sequence/test_sequence_memory.py::test_the_peak_memory_of_a_streamed_sequence_does_not_grow_with_its_length",
    "tests/sequence/test_window.py::test_bp1_on_the_window_gives_the_run_on_the_whole_grid",
    # full scene runs (SCEC builders on coarse grids)
    "tests/scenes/test_tpv_rate_state.py::test_tpv101_nucleates_at_the_hypocentre_on_a_coarse_grid",
    "tests/scenes/test_tpv_rate_state.py::test_a_coarse_half_space_run_nucleates",
    "tests/scenes/test_tpv5.py::test_tpv5_coarse_run_starts_at_the_hypocentre_and_keeps_the_surface_free",
    # ensembles on worker processes, killed workers and sweeps
    "tests/sequence/test_sequence_ensemble.py::test_a_sweep_of_bp1_gives_a_tidy_event_table",
    "tests/ensemble/test_ensemble_faults.py::test_worker_killed_mid_member_is_retried_or_marked_failed_then_resumed",
    "tests/ensemble/test_ensemble_faults.py::test_sweep_killed_leaves_a_stale_lock_that_the_next_sweep_takes_over",
    "tests/ensemble/test_ensemble_faults.py::test_two_sweeps_into_one_store_the_second_is_refused",
    "tests/ensemble/test_ensemble.py::test_failure_recorded_then_resumed_on_the_cluster",
    "tests/ensemble/test_ensemble.py::test_cli_workers_sizes_the_embedded_local_cluster",
    # the command line in fresh processes (each starts Python, cracklab and often dask)
    "tests/cli/test_cli_manners.py",
    # killed runs resumed, in fresh processes
    "tests/sequence/test_sequence_resume.py::test_kill_9_and_resume_is_bit_identical",
    "tests/output/test_resume.py::test_sigkill_mid_run_then_resume",
    "tests/output/test_resume.py::test_sigkill_inside_a_checkpoint_write",
    "tests/output/test_store_integrity.py::test_kill_during_the_final_write_leaves_a_store_not_complete",
    # object storage on the loopback S3 server: a killed process resumed, a sequence, a sweep run twice
    "tests/output/test_object_store_resume.py::test_sigkill_of_cracklab_run_into_s3_then_resume",
    "tests/output/test_object_store_lock.py::test_the_heartbeat_keeps_a_lock_fresh_and_a_stale_one_is_taken_over",
    "tests/output/test_object_store_lock.py::test_two_sweep_processes_started_at_once_on_one_s3_store",
    "tests/sequence/test_sequence_object_store.py::test_a_sequence_into_s3_is_the_in_memory_run_and_resumes_bit_for_bit",
    "tests/ensemble/test_object_store_members.py::test_a_member_rewritten_on_s3_is_never_served_as_complete",
    "tests/ensemble/test_object_store_verify.py::test_verify_of_an_ensemble_at_a_url_names_what_a_local_verify_names",
    "tests/ensemble/test_object_store_verify.py::test_a_sweep_into_a_url_recomputes_what_verify_names",
    "tests/ensemble/test_object_store_verify.py::test_readers_at_a_url_refuse_a_member_whose_metadata_was_changed",
    "tests/ensemble/test_object_store_verify.py::test_export_summary_and_plot_read_an_ensemble_at_a_url",
    "tests/ensemble/test_object_store_faults.py::test_members_of_a_sweep_whose_lock_was_taken_over_stop_writing",
    "tests/ensemble/test_object_store_faults.py::"
    "test_kill_9_of_the_sweep_driver_mid_member_then_the_rerun_completes_the_store",
    "tests/ensemble/test_object_store_faults.py::test_the_s3_server_restarted_mid_sweep",
    "tests/ensemble/test_object_store_faults.py::"
    "test_the_store_unreachable_longer_than_the_retries_ends_the_sweep_in_one_line",
    "tests/output/test_object_store_resume.py::test_the_store_unreachable_during_a_checkpoint",
    "tests/ensemble/test_object_store_faults.py::"
    "test_kill_9_of_a_dask_worker_mid_member_then_the_s3_store_is_complete",
    "tests/ensemble/test_object_store_faults.py::"
    "test_kill_9_of_the_driver_on_a_dask_scheduler_its_orphaned_members_stop_writing",
    # sweeps on the batch jobs of a one-node Slurm (tests/slurm.py) and on dask processes started
    # by hand, writing to the S3 server
    "tests/ensemble/test_cluster_slurm.py::test_a_sweep_on_slurm_jobs_writes_straight_to_s3_and_matches_a_local_run",
    "tests/ensemble/test_cluster_slurm.py::test_the_python_recipe_a_jobqueue_cluster_of_your_own_and_client",
    "tests/ensemble/test_cluster_slurm.py::test_ctrl_c_of_a_sweep_on_slurm_cancels_its_jobs",
    "tests/ensemble/test_cluster_slurm.py::test_slurm_refusing_the_jobs_is_one_line_naming_the_option",
    "tests/ensemble/test_cluster_processes.py::test_a_sweep_on_a_dask_scheduler_and_workers_started_by_hand",
    # studies' runs and compilations in fresh processes with empty caches
    "tests/studies/test_studies_quick.py::test_performance_study_quick_writes_one_table_per_thread_count",
    "tests/studies/test_studies_quick.py::test_performance_study_stages_quick",
    "tests/studies/test_regression_tools.py::test_tiny_case_is_identical_across_fresh_processes",
    "tests/laws/test_rate_state.py::test_the_fast_pass_compiles_to_vector_code",
    "tests/history/test_compile_order.py::test_engine_sums_do_not_depend_on_the_compile_order",
    # big grids
    "tests/solver/test_budget.py::test_the_estimate_agrees_with_the_peak_resident_memory",
    "tests/solver/test_budget.py::test_the_estimate_agrees_with_the_peak_of_a_bimaterial_and_a_rate_state_run",
    "tests/solver/test_budget.py::test_the_estimate_holds_the_traced_peak_of_a_bimaterial_and_a_rate_state_run",
    # kernel fits and the bimaterial faces' tables, from empty caches
    "tests/solver/test_face_kernels.py::test_exponential_fits_of_the_face_kernels",
    "tests/history/test_fast_engine.py::test_cache_round_trip_and_corruption",
    "tests/solver/test_face_fields.py::test_identical_faces_in_plane_split_the_slip_and_share_the_normal_motion",
    "tests/solver/test_face_fields.py::test_faces_differ_by_the_jump_at_snapshots_and_stations",
    "tests/solver/test_product2.py::test_bimaterial_pair_runs_product2",
    # rate-and-state runs (a Newton solve per point and step)
    "tests/sequence/test_spring_slider.py::test_the_error_follows_the_tolerance",
    "tests/sequence/test_spring_slider.py::test_the_fully_dynamic_response_is_the_same_ode",
    "tests/sequence/test_bp1_dynamic.py::test_the_first_event_of_bp1_fd_is_the_same_at_tolerances_1e_4_and_1e_6",
    "tests/sequence/test_spring_slider.py::test_the_dynamic_response_steps_by_the_pair_while_the_plane_is_slow",
    "tests/sequence/test_sequence_mirror.py::test_the_mirror_keeps_the_slip_rate_exactly_even_through_an_event",
    "tests/sequence/test_sequence_mirror.py::test_bp1s_earthquakes_stay_whole_with_the_mirror",
    "tests/sequence/test_sequence_resume.py::test_kill_9_and_resume_of_a_fully_dynamic_sequence_is_bit_identical",
    "tests/scenes/test_tpv6.py::test_the_default_domain_keeps_the_periodic_images_under_half_a_percent",
    "tests/laws/test_rate_state.py::test_psi_is_recorded_by_name_with_its_unit",
    "tests/laws/test_rate_state.py::test_following_the_normal_traction_is_the_constant_sigma_n_run",
    "tests/laws/test_rate_state.py::test_a_resumed_run_is_the_uninterrupted_run",
    "tests/laws/test_normal_regularisation.py::test_a_tiny_time_scale_is_the_unregularised_law",
    "tests/laws/test_normal_regularisation.py::test_rate_state_strength_uses_sigma_eff",
    "tests/cli/test_cli.py::test_bench_friction_laws",
    # the budget check of a sweep, the ensemble figures through the command line, the site build
    "tests/plots/test_plot.py::test_ensemble_figures_and_cli",
    "tests/solver/test_budget.py::test_a_sweep_checks_every_member_before_the_cluster_starts",
    "tests/docs/test_site.py",
})


# ----------------------------------------------------------------------------- object storage
@pytest.fixture(scope="session")
def s3_server():
    """An S3 API server (moto) on 127.0.0.1 and a free port, one for the session (under
    pytest-xdist: one per worker process), stopped at its end (tests/s3_server.py)."""
    server = S3Server().start()
    try:
        yield server
    finally:
        server.stop()


@pytest.fixture
def s3_env(s3_server, monkeypatch, tmp_path):
    """The environment that points clients at ``s3_server`` (endpoint, made-up keys, no
    ~/.aws), set for this test; yields the server."""
    for name, value in s3_server.env(str(tmp_path)).items():
        monkeypatch.setenv(name, value)
    for name in ("AWS_PROFILE", "AWS_SESSION_TOKEN", "AWS_ENDPOINT_URL_S3"):
        monkeypatch.delenv(name, raising=False)
    yield s3_server


# ----------------------------------------------------------------------------- a batch system
@pytest.fixture(scope="session")
def slurm_cluster(tmp_path_factory):
    """A one-node Slurm on loopback (tests/slurm.py), one for the session (under
    pytest-xdist: one per worker process), stopped at its end. Where Slurm is not
    installed (or not root) the tests that use it are skipped, saying why; in CI
    (CI=true, where `python3 bootstrap.py test` installs it) they fail."""
    why = slurm.missing()
    if why:
        if os.environ.get("CI", "").lower() in ("true", "1"):
            pytest.fail(f"CI runs the cluster tests: {why}")
        pytest.skip(why)
    cluster = slurm.Slurm(tmp_path_factory.mktemp("slurm")).start()
    try:
        yield cluster
    finally:
        cluster.stop()


@pytest.fixture
def slurm_env(slurm_cluster, monkeypatch):
    """SLURM_CONF set for this test (sbatch, squeue and scancel find ``slurm_cluster``); yields it."""
    for name, value in slurm_cluster.env.items():
        monkeypatch.setenv(name, value)
    yield slurm_cluster


@pytest.fixture
def s3_restartable(monkeypatch, tmp_path):
    """An S3 API server of this test's own that can be restarted with its data, or made
    unreachable for a while, on one endpoint (tests/s3_server.py, ``RestartableS3Server``),
    the environment pointed at it; yields the server. fsspec's cached file systems are
    dropped before and after (they hold the endpoint they were made with)."""
    import s3fs

    from s3_server import RestartableS3Server

    server = RestartableS3Server(tmp_path).start()
    for name, value in server.env(str(tmp_path)).items():
        monkeypatch.setenv(name, value)
    for name in ("AWS_PROFILE", "AWS_SESSION_TOKEN", "AWS_ENDPOINT_URL_S3", "AWS_MAX_ATTEMPTS", "AWS_RETRY_MODE"):
        monkeypatch.delenv(name, raising=False)
    s3fs.S3FileSystem.clear_instance_cache()
    try:
        yield server
    finally:
        server.stop()
        s3fs.S3FileSystem.clear_instance_cache()


def is_slow(nodeid: str) -> bool:
    """Whether a collected test's node id is listed in ``SLOW``."""
    path, _, name = nodeid.partition("::")
    return path in SLOW or f"{path}::{name.split('[')[0]}" in SLOW


def pytest_collection_modifyitems(config, items):
    for item in items:
        if is_slow(item.nodeid):
            item.add_marker(pytest.mark.slow)


# Collected in the process that runs pytest_sessionfinish (the controller under
# pytest-xdist, which receives every report with its user_properties).
_VALUES: dict[str, float] = {}
_OUTCOMES: dict[str, bool] = {}  # nodeid -> failed in some phase


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    for row_id, value in verification.drain():
        report.user_properties.append(("verification", (row_id, value)))


def pytest_runtest_logreport(report):
    for name, value in report.user_properties:
        if name == "verification":
            row_id, achieved = value
            achieved = float(achieved)
            _VALUES[row_id] = verification.worse(_VALUES.get(row_id, achieved), achieved)
    if report.skipped and report.when == "setup":
        return
    _OUTCOMES[report.nodeid] = _OUTCOMES.get(report.nodeid, False) or report.failed


def _achieved_now() -> dict:
    """Row id -> value (or "failed") for the rows whose tests ran in this session."""
    out = {}
    for rid, nodeid, *_rest, tol in verification.ROWS:
        ran = [failed for n, failed in _OUTCOMES.items() if verification.matches(nodeid, n)]
        if not ran:
            continue
        if rid in verification.OUTCOME_ROWS:
            out[rid] = sum(ran)
        elif rid in _VALUES:
            value = _VALUES[rid]
            # a failure elsewhere in the test must not show as a pass
            out[rid] = "failed" if any(ran) and not (math.isnan(value) or value > tol) else value
        elif any(ran):
            out[rid] = "failed"
    return out


def pytest_sessionfinish(session, exitstatus):
    if os.environ.get("CRACKLAB_WRITE_VERIFICATION") != "1":
        return
    if hasattr(session.config, "workerinput"):  # a pytest-xdist worker
        return
    now = _achieved_now()
    if not now:
        return
    text = DOC.read_text()
    old = {rid: cells["achieved"] for rid, cells in verification.parse_table(text).items()}
    achieved = {row[0]: now.get(row[0], old.get(row[0], "not run")) for row in verification.ROWS}
    DOC.write_text(verification.replace_table(text, verification.render_table(achieved)))
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write(f"\ncracklab: wrote {len(now)} verification rows to {DOC}\n")
