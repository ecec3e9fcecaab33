"""Real description files: a prolog of any length is read in linear time."""

from __future__ import annotations

import time

import pytest

from gimwatch.model.mjcf_model import is_mjcf, root_element_name

XACRO_HEADER = "".join(f"<!-- line {i} of the header xacro writes -->\n" for i in range(40))


@pytest.mark.parametrize(
    ("text", "root"),
    [
        (XACRO_HEADER + "<robot name='iiwa'></robot>", "robot"),
        ('<?xml version="1.0"?>\n' + XACRO_HEADER + "<mujoco model='m'/>", "mujoco"),
        ("\ufeff<mujoco model='bom'/>", "mujoco"),
        ("<!DOCTYPE robot [<!ENTITY a 'b'>]>\r\n<robot name='x'/>", "robot"),
        ("<!-- never closed " + "<!-- " * 1000, None),
        ("plain text", None),
        ("<mujocox/>", "mujocox"),
    ],
)
def test_root_element_name(text, root):
    assert root_element_name(text) == root
    assert is_mjcf(text) == (root == "mujoco")


def test_prolog_scan_is_linear_not_exponential():
    # 100,000 leading comments and a 10 MB comment: the old nested regex never returned.
    many = "<!-- c -->\n" * 100_000 + "<robot name='x'/>"
    huge = "<!--" + "x" * 10_000_000 + "-->\n<robot name='x'/>"
    start = time.perf_counter()
    assert root_element_name(many) == "robot"
    assert root_element_name(huge) == "robot"
    assert time.perf_counter() - start < 60  # a generous bound: linear takes ~0.1 s
