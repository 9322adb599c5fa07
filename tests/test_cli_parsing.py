"""Tests of amlip_qp.cli.parsing: the parser class, lazy handlers and the options' value types."""

from __future__ import annotations

import argparse

import pytest

from amlip_qp.cli import parsing as P


def test_parse_push_spec():
    assert P.parse_push_spec("6:100,0,-5.5:0.2") == (6.0, (100.0, 0.0, -5.5), 0.2)
    for bad in ("6:100,0:0.2", "6:100,0,0", "6:100,0,0:0.2:1", "6:nan,0,0:0.2", "x:1,0,0:1", "6:1,0,0:-1"):
        with pytest.raises(argparse.ArgumentTypeError):
            P.parse_push_spec(bad)


@pytest.mark.parametrize(
    "parse, good, bad",
    [
        (P.finite_float, [("-1e-1", -0.1), ("0", 0.0)], ["inf", "nan", "x"]),
        (P.positive_float, [("2.5", 2.5)], ["0", "-1", "inf"]),
        (P.non_negative_float, [("0", 0.0), ("3", 3.0)], ["-0.5", "nan"]),
        (P.positive_int, [("1", 1), ("40", 40)], ["0", "-3", "1.5"]),
        (P.non_negative_int, [("0", 0)], ["-1", "x"]),
        (P.name_list(("pbc", "qp")), [("qp,pbc,qp", ["qp", "pbc"]), (" pbc ", ["pbc"])], ["", "pbc,lqr"]),
        (P.float_in(0.0, 240.0, "frames/s"), [("240", 240.0), ("1e-3", 1e-3)], ["0", "240.5", "1e9", "nan", "-inf"]),
        (P.float_in(0.0005, 600.0, "s", low_open=False), [("0.0005", 0.0005), ("600", 600.0)], ["1e-9", "601"]),
        (P.int_in(1, 64, "number of worker processes"), [("1", 1), ("64", 64)], ["0", "65", "1e3", "2.5"]),
    ],
)
def test_value_types_take_good_values_and_refuse_bad_ones_in_one_line(parse, good, bad):
    for text, value in good:
        assert parse(text) == value
    for text in bad:
        with pytest.raises(argparse.ArgumentTypeError) as err:
            parse(text)
        assert repr(text) in str(err.value) or repr(int(text)) in str(err.value)
        assert "\n" not in str(err.value)


def test_parser_reads_negative_numbers_as_values_and_errors_in_one_line(capsys):
    parser = P.Parser(prog="x")
    parser.add_argument("--vx", type=P.finite_float)
    assert parser.parse_args(["--vx", "-1e-1"]).vx == -0.1
    with pytest.raises(SystemExit) as exc:
        parser.parse_args(["--vx", "fast"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and err.startswith("x: error: argument --vx")


def test_handler_imports_its_module_only_when_run(monkeypatch):
    import sys

    monkeypatch.delitem(sys.modules, "amlip_qp.output_paths", raising=False)
    run = P.handler("amlip_qp.output_paths:check_output_path")
    assert "amlip_qp.output_paths" not in sys.modules  # not imported by making the handler
    with pytest.raises(TypeError):  # check_output_path(args): imported and called with the wrong arguments
        run(argparse.Namespace())
    assert "amlip_qp.output_paths" in sys.modules


def test_bounded_types_name_the_interval_and_the_unit():
    with pytest.raises(argparse.ArgumentTypeError) as err:
        P.float_in(0.0, 240.0, "frames/s")("1e9")
    assert str(err.value) == "expected a number in (0, 240] frames/s, got '1e9'"
    with pytest.raises(argparse.ArgumentTypeError) as err:
        P.float_in(0.0005, 600.0, "s", low_open=False)("0")
    assert str(err.value) == "expected a number in [0.0005, 600] s, got '0'"
    with pytest.raises(argparse.ArgumentTypeError) as err:
        P.int_in(0, 20, "number of iterations")("1000000000")
    assert str(err.value) == "expected a number of iterations in [0, 20], got 1000000000"
