"""The suite's xdist groups reach the scheduler (conftest's ``@<group>`` node ids)."""

import pytest


@pytest.mark.xdist_group("harness_probe")
def test_a_grouped_test_carries_its_group_in_its_node_id(request):
    """Under ``--dist loadgroup`` the scheduler sends the tests of one group to one
    worker by this suffix; without it every group is split across the workers."""
    loadgroup = getattr(request.config.option, "loadgroup", False)  # set in xdist workers
    assert request.node.nodeid.endswith("@harness_probe") == bool(loadgroup)
