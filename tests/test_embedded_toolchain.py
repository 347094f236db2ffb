"""Toolchain lookup: missing tools are reported with their Debian package."""

from __future__ import annotations

import pytest

from stt_codegen.embedded import toolchain
from stt_codegen.embedded.toolchain import (MissingTool, find_tool, find_toolchain,
                                             missing_message, missing_tools)
from stt_codegen.errors import SttError


def test_missing_tool_names_debian_package() -> None:
    err = MissingTool("qemu-system-arm", "qemu-system-arm")
    assert isinstance(err, SttError)
    assert "apt-get install -y qemu-system-arm" in str(err)
    assert err.tool == "qemu-system-arm" and err.package == "qemu-system-arm"


def test_every_tool_has_a_package() -> None:
    for tool in toolchain.BUILD_TOOLS + toolchain.RUN_TOOLS:
        assert toolchain.DEBIAN_PACKAGES[tool]


def test_empty_path_reports_each_package(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    missing = missing_tools()
    packages = {m.package for m in missing}
    assert {"gcc-arm-none-eabi", "binutils-arm-none-eabi", "qemu-system-arm"} <= packages
    with pytest.raises(MissingTool) as info:
        find_tool("arm-none-eabi-size")
    assert info.value.package == "binutils-arm-none-eabi"
    with pytest.raises(MissingTool):
        find_toolchain()
    message = missing_message()
    assert message is not None and message.count("gcc-arm-none-eabi") == 1
    assert "binutils-arm-none-eabi" in message and "qemu-system-arm" in message


@pytest.mark.embedded
def test_installed_toolchain_found() -> None:
    tc = find_toolchain()
    assert tc.gcc.name == "arm-none-eabi-gcc" and tc.qemu is not None
