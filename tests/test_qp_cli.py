"""`amlip-qp bench qp`: argument errors exit 2 with one readable line."""

import pytest

from amlip_qp.cli import main


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["bench", "qp", "--ticks", "0"], "expected a positive integer"),
        (["bench", "qp", "--ticks", "many"], "expected a positive integer"),
        (["bench", "qp", "--scenario", "moonwalk"], "unknown scenario 'moonwalk'"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(argv, needle, capsys):
    with pytest.raises(SystemExit) as info:
        code = main(argv)
        raise SystemExit(code)
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]
