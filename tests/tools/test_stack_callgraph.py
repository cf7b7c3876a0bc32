"""The static call graph decodes code only: literal pools ($d regions) are not instructions."""
import pytest

from codegen import artifact as art
from codegen.units.network.unit import NetworkUnit
from tools import stack
from tools.m4.elf import Image
from tools.runners import arm_build


@pytest.fixture(scope="module")
def network_image():
    a = art.random_artifact((12, 40, 3), seed=3)
    build = arm_build(NetworkUnit(a))
    return Image(build.elf), build


def test_code_ranges_skip_data_marked_by_mapping_symbols(network_image):
    image, _ = network_image
    f = image.function("network_hidden")  # the MLP loop, with a literal pool
    pieces = image.code_ranges(f.start, f.size)
    data_marks = [addr for addr, kind in image.mapping if kind == "d" and f.start < addr < f.start + f.size]
    assert pieces and pieces[0][0] == f.start
    for addr in data_marks:  # no decoded piece covers the start of a data region
        assert all(not (a <= addr < a + n) for a, n in pieces)


def test_call_graph_of_the_network_path_is_exact(network_image):
    image, build = network_image
    graph, indirect = stack.call_graph(image)
    # normalise inline, then a tail call of the MLP loop (which denormalises too): no other call,
    # tanh inline (the stage functions network_normalise/mlp/denormalise are not in the step).
    assert graph["network_eval"] == {"network_hidden"}
    assert not graph.get("network_hidden")
    bound = stack.worst_case(image, build.su_files, "network_eval")
    assert bound.problems == [] and bound.bytes is not None and 0 < bound.bytes <= 512
