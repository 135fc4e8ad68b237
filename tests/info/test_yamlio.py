import math
from pathlib import Path

import pytest
import yaml

from cellengine.errors import InputError
from cellengine.info import yamlio
from cellengine.info.yamlio import parse_yaml

F = Path("f.yaml")


def err(text: str) -> str:
    with pytest.raises(InputError) as e:
        parse_yaml(text, F)
    return str(e.value)


def test_positions_of_values_and_keys() -> None:
    doc = parse_yaml("a:\n  b: [1, 2]\n  c: x\n", F)
    assert doc.data == {"a": {"b": [1, 2], "c": "x"}}
    assert doc.values[("a", "b", 1)] == (2, 10)
    assert doc.keys[("a", "c")] == (3, 3)
    assert doc.where(("a", "zz")) == (2, 3)  # nearest enclosing value


def test_merge_keys_and_anchors_work() -> None:
    doc = parse_yaml("base: &b {x: 1}\nfoo:\n  <<: *b\n  y: 2\n", F)
    assert doc.data["foo"] == {"x": 1, "y": 2}


def test_python_tags_are_refused() -> None:
    assert err("a: !!python/object/apply:os.system [ls]\n") == (
        "f.yaml:1:4: YAML tag '!!python/object/apply:os.system' is not allowed; "
        "only plain maps, lists, strings, numbers, booleans and null"
    )


def test_duplicate_keys_are_errors() -> None:
    assert err("a: 1\nb: 2\na: 3\n") == "f.yaml:3:1: duplicate key 'a' (first given at line 1)"


def test_alias_bomb_refused_before_expansion() -> None:
    lines = ['a: &a ["x","x","x","x","x","x","x","x","x"]']
    for prev, name in zip("abcdefg", "bcdefgh", strict=True):
        lines.append(f"{name}: &{name} [" + ",".join([f"*{prev}"] * 9) + "]")
    assert err("\n".join(lines) + "\n") == (
        "f.yaml:6:4: YAML expands to more than 100000 values (an alias bomb?)"
    )


def test_too_many_aliases(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(yamlio, "MAX_ALIASES", 3)
    assert (
        err("a: &a 1\nb: [*a, *a, *a, *a]\n") == "f.yaml:1:4: YAML uses more than 3 aliases"
    )  # at the anchor


def test_syntax_error_has_line_and_column() -> None:
    assert err("a: [1, 2\nb: 3\n") == (
        "f.yaml:2:2: YAML syntax error: expected ',' or ']', but got ':'"
    )


def test_size_cap(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from cellengine.info import files

    monkeypatch.setitem(files.MAX_BYTES, "yaml", 10)
    p = tmp_path / "big.yaml"
    p.write_text("a: 123456789012\n")
    with pytest.raises(InputError) as e:
        yamlio.load_yaml(p)
    assert "more than the 10-byte limit for yaml files" in str(e.value)


def test_empty_document() -> None:
    assert parse_yaml("# nothing\n", F).data is None


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1e30", 1e30),
        ("5e-324", 5e-324),
        ("-1.5E-3", -1.5e-3),
        ("+.5e+3", 500.0),
        ("1.", 1.0),
        ("17", 17),
        ("017", 17),  # a leading 0 is decimal in YAML 1.2
        ("0o17", 15),
        ("0x1F", 31),
        ("-0", 0),
        (".inf", math.inf),
        ("-.Inf", -math.inf),
        ("+.INF", math.inf),
        ("true", True),
        ("True", True),
        ("FALSE", False),
        ("~", None),
        ("Null", None),
        # strings in YAML 1.2, numbers or booleans in PyYAML's YAML 1.1
        ("1:20", "1:20"),
        ("1_000", "1_000"),
        ("0b101", "0b101"),
        ("-0x1F", "-0x1F"),
        ("yes", "yes"),
        ("no", "no"),
        ("on", "on"),
        ("Off", "Off"),
        ("2024-01-01", "2024-01-01"),
        ("=", "="),
        ("NaN", "NaN"),
    ],
)
def test_scalars_resolve_as_yaml_1_2_core(text: str, value: object) -> None:
    got = parse_yaml(f"a: {text}\n", F).data["a"]
    assert got == value and type(got) is type(value)


def test_nan_as_yaml_1_2_writes_it() -> None:
    for text in (".nan", ".NaN", ".NAN"):
        assert math.isnan(parse_yaml(f"a: {text}\n", F).data["a"])


def test_keys_stay_as_written() -> None:
    assert parse_yaml("on: 1\n017: 2\n", F).data == {"on": 1, "017": 2}


def test_explicit_tags_need_yaml_1_2_numbers() -> None:
    assert parse_yaml('a: !!int "12"\nb: !!float 3\n', F).data == {"a": 12, "b": 3.0}
    assert err("a: !!int 1_000\n") == (
        "f.yaml:1:4: bad YAML value: '1_000' is not an integer in YAML 1.2"
    )
    assert (
        err("a: !!float 1:20\n") == "f.yaml:1:4: bad YAML value: '1:20' is not a number in YAML 1.2"
    )
    assert err("a: !!bool yes\n") == (
        "f.yaml:1:4: bad YAML value: 'yes' is not true or false in YAML 1.2"
    )


def test_a_float_beyond_the_largest_is_refused() -> None:
    assert err("a: [1, -1e999]\n") == (
        "f.yaml:1:8: bad YAML value: the number -1e999 is beyond the largest float (1.8e308)"
    )


def test_pyyaml_loaders_keep_yaml_1_1() -> None:
    """Our resolvers are our loader's own: other users of PyYAML are not changed."""
    assert yaml.safe_load("a: yes\nb: 1e30\n") == {"a": True, "b": "1e30"}


def test_an_integer_beyond_the_largest_float_is_refused() -> None:
    assert err("a: 0x" + "f" * 300 + "\n") == (
        "f.yaml:1:4: bad YAML value: the number 0xfffffffffffffffffffffffffffffffffff... is "
        "beyond the largest float (1.8e308)"
    )
    assert parse_yaml(f"a: {10**300}\n", F).data["a"] == 10**300  # as large as a float may be
