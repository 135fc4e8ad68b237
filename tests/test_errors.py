from cellengine.errors import InputError, Problem, printable


def test_printable_escapes_controls_as_python_writes_them() -> None:
    text = "a\x1b[31mb\n::error::x\t\r\x00\x7f\x9b\u2028\u202e\ud800 é ✓"
    assert printable(text) == (
        "a\\x1b[31mb\\n::error::x\\t\\r\\x00\\x7f\\x9b\\u2028\\u202e\\ud800 é ✓"
    )
    assert printable(printable(text)) == printable(text)  # nothing left to escape


def test_a_problem_prints_on_one_line() -> None:
    p = Problem("unknown key 'a\n::error::x'", "f\x1b.yaml", 3, 1)
    assert str(p) == "f\\x1b.yaml:3:1: unknown key 'a\\n::error::x'"
    assert p.message == "unknown key 'a\n::error::x'"  # the data stays as read
    assert str(InputError([p, p])).splitlines() == [str(p), str(p)]


def test_a_problem_of_no_file_is_its_message_alone() -> None:
    """A refusal or a driver's hint is about no file: no stray '<input>:' before it."""
    p = Problem("not confirmed: nothing moved")
    assert (p.location(), str(p)) == ("", "not confirmed: nothing moved")
    assert p.warning() == "warning: not confirmed: nothing moved"
    assert str(Problem("bad", "cell.yaml")) == "cell.yaml: bad"
