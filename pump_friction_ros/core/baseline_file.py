# Copyright 2026 pump_friction_ros developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
The healthy baseline file: what the wear monitor learnt, with where it was learnt.

A YAML file holding ``WearMonitor.state_dict()``, how much running it was learnt from (the
monitored samples and the stamps of the first and the latest), wall times, and its
*provenance*: the pump file's content hash, the table's fingerprint and the node parameters
that change the residual or what the monitor learns from (`PROVENANCE_PARAMETERS`). A file
is used only by an estimator of the same provenance: the state of another pump, table or
parameters is refused with one line naming what differs (`BaselineMismatchError`).

Written atomically (`write_baseline`, through ``baseline_disk.replace_file``: a temporary
file in the same folder, flushed and fsynced, then ``os.replace``), so a crash or power cut
leaves the previous file or the new one, never half of one. ``baseline_store`` is the
node's side (load at start, save, reset after a repair, the status for /diagnostics).
docs/node.md, "The healthy baseline file".
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
import time
from typing import Any, TYPE_CHECKING

import yaml

from .baseline_disk import replace_file
from .. import __version__, MODEL_VERSION
from ..errors import BaselineError, BaselineMismatchError, ConfigError, quote
from ..yaml_files import read_yaml, SafeDumper

if TYPE_CHECKING:
    from .estimator import TorqueEstimator
    from .node_parameters import EstimatorConfig
    from ..table.friction_table import FrictionTable

__all__ = ['BASELINE_FORMAT', 'BASELINE_FORMAT_VERSION', 'PROVENANCE_PARAMETERS',
           'baseline_document', 'load_baseline', 'provenance', 'provenance_differences',
           'read_baseline', 'restore_baseline', 'table_fingerprint', 'utc_now',
           'write_baseline']

BASELINE_FORMAT = 'pump_friction_ros healthy baseline'
BASELINE_FORMAT_VERSION = 1
"""Version of the file's layout (the monitor's state has its own, ``STATE_VERSION``)."""

PROVENANCE_PARAMETERS = (
    'joint_name', 'speed_source', 'torque_source', 'pressure_source', 'viscosity_source',
    'rotor_inertia_kg_m2', 'accel_filter_time_constant_s', 'drive_loss_torque_nm',
    'monitor_min_speed_rad_s', 'monitor_max_accel_rad_s2', 'monitor_settle_s',
    'monitor_lookahead_s', 'attribution_window_s')
"""Node parameters that change the residual, which samples the monitor learns from or how
it averages them into windows; the
oil's (``oil_viscosity_m2_s``, or the two of the temperature law) join them by
``viscosity_source``. The detection and attribution tuning is not among them: retuning a
threshold keeps what was learnt."""

_HEADER = ("# Healthy baseline of pump_friction_ros's wear monitor: written by the node or by\n"
           '# pump_friction learn-baseline, checked against the provenance when loaded; do not\n'
           '# edit. Re-learn after a repair: ~/reset_monitor or pump_friction reset-baseline.\n')
_DUMPER = SafeDumper  # (quotes a string that the loader would read as a number)

# -- provenance ---------------------------------------------------------------------------


def table_fingerprint(table: FrictionTable) -> str:
    """
    Return what identifies a table's content: its pump, model version and axes (SHA-256).

    The torques are a function of these (and the model, whose version is in it), so a table
    rebuilt from the same pump file and envelope, on any machine, has the same fingerprint;
    the axes are rounded to 12 significant digits so that their last bits do not count.

    Parameters
    ----------
    table : FrictionTable
        The table.

    Returns
    -------
    str
        Hex digest.

    """
    meta = table.metadata
    content = {
        'pump_sha256': str(meta.get('pump_sha256')),
        'model_version': str(meta.get('model_version')),
        'n_angles': meta.get('n_angles'),
        'axes': [[format(float(x), '.12g') for x in axis] for axis in (
            table.speed_axis_rad_s, table.pressure_axis_pa, table.viscosity_axis_m2_s)],
    }
    return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()


def _parameters(config: EstimatorConfig) -> dict[str, Any]:
    """Return the `PROVENANCE_PARAMETERS` and the oil's, as plain YAML values."""
    names = list(PROVENANCE_PARAMETERS)
    names += ['oil_viscosity_40c_m2_s', 'oil_viscosity_100c_m2_s'] \
        if str(config.viscosity_source) == 'temperature' else ['oil_viscosity_m2_s']
    values = {}
    for name in names:
        value = getattr(config, name)
        values[name] = value if isinstance(value, (bool, int, float)) else str(value)
    return values


def provenance(core: TorqueEstimator) -> dict[str, Any]:
    """
    Return what a baseline learnt by ``core`` depends on, the part of the file compared.

    Parameters
    ----------
    core : TorqueEstimator
        The estimator.

    Returns
    -------
    dict
        ``pump`` (name, SHA-256 of the pump file's parameters), ``table`` (fingerprint,
        model version) and ``parameters`` (the node parameters that matter).

    """
    table = core.table
    return {
        'pump': {'name': core.pump_name, 'sha256': table.pump_sha256},
        'table': {'fingerprint': table_fingerprint(table),
                  'model_version': str(table.metadata.get('model_version', MODEL_VERSION))},
        'parameters': _parameters(core.config),
    }


def provenance_differences(saved: dict[str, Any], current: dict[str, Any]) -> list[str]:
    """
    Return what differs between a file's provenance and the estimator's, one phrase each.

    Parameters
    ----------
    saved : dict
        The file's ``provenance``.
    current : dict
        `provenance` of the estimator.

    Returns
    -------
    list of str
        E.g. ``drive_loss_torque_nm (file 0.05, now 0.1)``; empty when they agree.

    """
    found = []
    pump, now = saved.get('pump', {}), current['pump']
    if pump.get('sha256') != now['sha256']:
        found.append(f'another pump file (file {pump.get("name")} sha256 '
                     f'{str(pump.get("sha256"))[:12]}, now {now["name"]} sha256 '
                     f'{now["sha256"][:12]})')
    table, now = saved.get('table', {}), current['table']
    if table.get('fingerprint') != now['fingerprint']:
        found.append(f'another table (file model version {table.get("model_version")} '
                     f'fingerprint {str(table.get("fingerprint"))[:12]}, now model version '
                     f'{now["model_version"]} fingerprint {now["fingerprint"][:12]})')
    params, now = saved.get('parameters', {}), current['parameters']
    for name in sorted(set(params) | set(now)):
        if params.get(name) != now.get(name):
            found.append(f'{name} (file {_shown(params.get(name))}, '
                         f'now {_shown(now.get(name))})')
    return found


def _shown(value: Any) -> str:
    return 'absent' if value is None else (f'{value:g}' if isinstance(value, float)
                                           else quote(value, 40))


# -- the document -------------------------------------------------------------------------


def utc_now() -> str:
    """Return the UTC wall time, ISO 8601 to the second."""
    return time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())


def baseline_document(core: TorqueEstimator, created_utc: str = '', origin: str = ''
                      ) -> dict[str, Any]:
    """
    Return the baseline file's content for what ``core``'s monitor has learnt.

    Parameters
    ----------
    core : TorqueEstimator
        The estimator.
    created_utc : str
        When this baseline began (the last reset); empty: now.
    origin : str
        Who learnt it, for a reader (``node /torque_estimator``, the bags).

    Returns
    -------
    dict
        Plain YAML values: format and its version, package version, wall times,
        ``learnt`` (samples; first and latest stamps [ns]), ``provenance``, ``about``
        (informative: origin, pump and table files) and ``monitor_state``.

    """
    samples, first_ns, last_ns = core.learnt
    now = utc_now()
    return {
        'format': BASELINE_FORMAT,
        'format_version': BASELINE_FORMAT_VERSION,
        'package_version': __version__,
        'created_utc': created_utc or now,
        'updated_utc': now,
        'learnt': {'samples': samples, 'first_stamp_ns': first_ns, 'last_stamp_ns': last_ns},
        'provenance': provenance(core),
        'about': {'origin': origin, 'pump_file': core.config.pump_file or '(the default)',
                  'table_file': core.config.table_file or '(the cached one)'},
        'monitor_state': core.monitor.state_dict(),
    }


def write_baseline(path: Path, document: dict[str, Any]) -> None:
    """
    Write a baseline file atomically: the old file, or the new one, never half of one.

    A temporary file in the same folder is written, flushed and fsynced, then renamed over
    ``path`` (``os.replace``) and the folder fsynced; on any failure it is removed and
    ``path`` is left as it was. An existing file's permissions are kept.

    Parameters
    ----------
    path : Path
        The baseline file; its folder is made when missing.
    document : dict
        `baseline_document`'s content.

    Raises
    ------
    OutputError
        The folder or file cannot be written (one line, with the reason).
    BaselineError
        The document holds something other than plain values.

    """
    try:
        text = _HEADER + yaml.dump(document, Dumper=_DUMPER, sort_keys=False,
                                   default_flow_style=False, allow_unicode=True)
    except yaml.YAMLError as exc:
        raise BaselineError(f'baseline for {path}: not plain values: {exc}') from None
    replace_file(path, text)


def read_baseline(path: Path) -> dict[str, Any]:
    """
    Read a baseline file and check its layout (not yet its provenance).

    Parameters
    ----------
    path : Path
        The file.

    Returns
    -------
    dict
        The document (`baseline_document`'s keys).

    Raises
    ------
    BaselineError
        Missing, unreadable, not YAML, not a baseline file, another format version, or
        malformed entries: one line naming the file.

    """
    try:
        doc = read_yaml(path, 'baseline file', ros_numbers=False)  # as it was written
    except ConfigError as exc:
        raise BaselineError(str(exc)) from None
    if not isinstance(doc, dict) or doc.get('format') != BASELINE_FORMAT:
        raise BaselineError(f'{path}: not a {BASELINE_FORMAT} file')
    version = doc.get('format_version')
    if type(version) is not int or version != BASELINE_FORMAT_VERSION:  # (True == 1.0 == 1)
        raise BaselineError(f'{path}: format_version {quote(version)}, this package reads '
                            f'{BASELINE_FORMAT_VERSION}')
    for key in ('learnt', 'provenance', 'monitor_state'):
        if not isinstance(doc.get(key), dict):
            raise BaselineError(f'{path}: {key}: expected a mapping, got '
                                f'{quote(doc.get(key))}')
    learnt = doc['learnt']
    samples = learnt.get('samples')
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 0:
        raise BaselineError(f'{path}: learnt.samples: expected a count, got {quote(samples)}')
    for key in ('first_stamp_ns', 'last_stamp_ns'):
        value = learnt.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                                  or not 0 <= value < 2**63):
            raise BaselineError(f'{path}: learnt.{key}: expected a stamp [ns] or null, got '
                                f'{quote(value)}')
    # (first after last is possible: a clock restart, simulated time replayed again)
    prov = doc['provenance']
    for key in ('pump', 'table', 'parameters'):
        if not isinstance(prov.get(key), dict):
            raise BaselineError(f'{path}: provenance.{key}: expected a mapping, got '
                                f'{quote(prov.get(key))}')
    if not isinstance(doc.get('created_utc', ''), str):
        raise BaselineError(f'{path}: created_utc: expected a string')
    return doc


def restore_baseline(core: TorqueEstimator, document: dict[str, Any], path: Path) -> None:
    """
    Load a read document into ``core`` if its provenance is ``core``'s.

    Parameters
    ----------
    core : TorqueEstimator
        The estimator; its monitor takes the state, or is left as it was on a mismatch
        and reset on a state it refuses.
    document : dict
        `read_baseline`'s result.
    path : Path
        The file, for messages.

    Raises
    ------
    BaselineMismatchError
        Another pump file, table or node parameters; the message names each difference.
    BaselineError
        A monitor state the monitor refuses (another ``STATE_VERSION``, malformed).

    """
    differences = provenance_differences(document['provenance'], provenance(core))
    if differences:
        raise BaselineMismatchError(f'{path}: learnt on another pump, table or parameters: '
                                    f'{"; ".join(differences)}')
    learnt = document['learnt']
    try:
        core.restore_monitor(document['monitor_state'], learnt['samples'],
                             learnt.get('first_stamp_ns'), learnt.get('last_stamp_ns'))
    except ValueError as exc:
        raise BaselineError(f'{path}: monitor_state: {" ".join(str(exc).split())}') from None


def load_baseline(core: TorqueEstimator, path: Path) -> dict[str, Any]:
    """
    Read a baseline file and load it into ``core`` (the replay's ``--baseline``).

    Parameters
    ----------
    core : TorqueEstimator
        The estimator.
    path : Path
        The file.

    Returns
    -------
    dict
        The document.

    Raises
    ------
    BaselineError
        As `read_baseline` and `restore_baseline`.

    """
    document = read_baseline(path)
    restore_baseline(core, document, path)
    return document
