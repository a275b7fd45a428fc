"""Helpers of the command-line tests (imported by tests/test_cli*.py, which sit beside it)."""
from sosdyn.cli import main


def run(capsys, *argv):
    """Run the CLI in-process; return (exit code, stdout, stderr)."""
    try:
        main([str(a) for a in argv])
        code = 0
    except SystemExit as exc:
        code = exc.code or 0
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def assert_one_error_line(code, err, *fragments, need_try=False):
    """Exit status 1 and one stderr line ``error: ...`` holding every fragment (and ``Try: ``)."""
    assert code == 1, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: "), lines[0]
    assert "Traceback" not in err
    assert not need_try or "Try: " in lines[0], lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
