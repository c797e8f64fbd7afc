"""External validators for what the writers produce: Khronos glTF-Validator and USD validation.

glTF: the npm package ``gltf-validator`` (the Khronos validator compiled to
JavaScript), installed into ``.tools/node_modules`` by
``tools/install_validators.sh`` and run with ``node`` through its
``validateBytes`` API. The tools folder is ``$PLANEFMT_TOOLS`` if set, else
``.tools`` at the root of the source tree this package runs from.

USD: usd-core's validation framework (``pxr.UsdValidation``), with the
validator set ``usdchecker --useNewValidationFramework`` uses (all registered
validators except the ARKit-only ``UsdzValidators`` group and the
root-package-only check), plus ``usdUtilsValidators:UsdzPackageValidator``
for ``.usdz`` packages.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

#: Reads the file named by argv[2] (and its external buffers) and prints the
#: validator's JSON report; argv[1] is the gltf-validator package folder.
_GLTF_SCRIPT = r"""
const fs = require("fs");
const path = require("path");
const validator = require(process.argv[1]);
const file = path.resolve(process.argv[2]);
validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
  uri: path.basename(file),
  maxIssues: 0,
  writeTimestamp: false,
  externalResourceFunction: (uri) => new Promise((resolve, reject) => {
    fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)),
                (err, data) => err ? reject(err.toString()) : resolve(new Uint8Array(data)));
  }),
}).then(
  (report) => process.stdout.write(JSON.stringify(report)),
  (error) => { process.stderr.write(String(error)); process.exit(2); });
"""

_USDZ_ONLY = "UsdzValidators"
_ROOT_PACKAGE = "usdUtilsValidators:RootPackageValidator"
_USDZ_PACKAGE = "usdUtilsValidators:UsdzPackageValidator"


class ValidatorUnavailable(RuntimeError):
    """The external validator is not installed (node, the npm package or pxr missing)."""


def tools_dir() -> Path:
    """Where ``tools/install_validators.sh`` puts the external validators."""
    configured = os.environ.get("PLANEFMT_TOOLS")
    if configured:
        return Path(configured)
    return Path(__file__).resolve().parent.parent / ".tools"


def gltf_validator() -> tuple[str, Path]:
    """``(node executable, gltf-validator package folder)``, or ValidatorUnavailable."""
    node = shutil.which("node")
    if node is None:
        raise ValidatorUnavailable("node is not on PATH")
    package = tools_dir() / "node_modules" / "gltf-validator"
    if not (package / "package.json").is_file():
        raise ValidatorUnavailable(
            f"gltf-validator is not installed in {package.parent}: run tools/install_validators.sh")
    return node, package


def validate_gltf(path: str | os.PathLike[str], *, timeout: float = 120.0) -> dict[str, Any]:
    """The Khronos glTF-Validator report for a ``.gltf`` or ``.glb`` file.

    The report is the validator's JSON as a dict; ``report["issues"]`` holds
    ``numErrors``, ``numWarnings``, ``numInfos``, ``numHints`` and the
    ``messages`` (code, message, severity 0=error … 3=hint, pointer).
    Raises :class:`ValidatorUnavailable` when node or the package is
    missing, RuntimeError when the validator cannot run on the file at all.
    """
    node, package = gltf_validator()
    result = subprocess.run([node, "-e", _GLTF_SCRIPT, str(package), os.fspath(path)],
                            capture_output=True, text=True, timeout=timeout, check=False)
    if result.returncode != 0:
        raise RuntimeError(f"glTF-Validator failed on {path}: {result.stderr.strip()}")
    return json.loads(result.stdout)


def validate_usd(path: str | os.PathLike[str]) -> list[tuple[str, str]]:
    """``(severity, message)`` findings of USD validation on a stage file.

    Severity is ``"error"``, ``"warning"`` or ``"info"``. A stage that does
    not open is one error finding. Raises :class:`ValidatorUnavailable`
    when ``pxr`` (usd-core) is missing.
    """
    try:
        from pxr import Usd, UsdValidation
    except ImportError as exc:
        raise ValidatorUnavailable(f"usd-core is not installed: {exc}") from exc
    file = os.fspath(path)
    try:
        stage = Usd.Stage.Open(file)
    except Exception as exc:  # noqa: BLE001 - Tf.ErrorException
        return [("error", f"cannot open stage: {exc}")]
    if stage is None:
        return [("error", "cannot open stage")]
    registry = UsdValidation.ValidationRegistry()
    names = [meta.name for meta in registry.GetAllValidatorMetadata()
             if _USDZ_ONLY not in meta.GetKeywords() and meta.name != _ROOT_PACKAGE]
    if file.lower().endswith(".usdz"):
        names.append(_USDZ_PACKAGE)
    # A list of validators, not of metadata: the bindings would read a
    # metadata list as schema types.
    context = UsdValidation.ValidationContext(registry.GetOrLoadValidatorsByName(sorted(names)))
    severity = {UsdValidation.ValidationErrorType.Error: "error",
                UsdValidation.ValidationErrorType.Warn: "warning"}
    return [(severity.get(error.GetType(), "info"), error.GetErrorAsString())
            for error in context.Validate(stage)]
