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
    f = image.function("network_mlp")
    pieces = image.code_ranges(f.start, f.size)
    data_marks = [addr for addr, kind in image.mapping if kind == "d" and f.start < addr < f.start + f.size]
    assert pieces and pieces[0][0] == f.start
    for addr in data_marks:  # no decoded piece covers the start of a data region
        assert all(not (a <= addr < a + n) for a, n in pieces)


def test_call_graph_of_the_network_path_is_exact(network_image):
    image, build = network_image
    graph, indirect = stack.call_graph(image)
    assert graph["network_eval"] == {"network_normalise", "network_mlp", "network_denormalise"}
    assert graph["network_mlp"] <= {"sg_tanhf"}  # tanh may be inlined, nothing else may appear
    assert not graph.get("network_normalise") and not graph.get("network_denormalise")
    bound = stack.worst_case(image, build.su_files, "network_eval")
    assert bound.problems == [] and bound.bytes is not None and 0 < bound.bytes <= 512
