"""``sources/buildDescription.xml``: how an importer compiles the FMU's sources.

FMI 3.0 defines this file (section 2.5.1.4, schema ``fmi3BuildDescription.xsd``) and allows
it in FMUs of earlier versions; flexsat writes it into FMUs of both versions, so that a
sources-only FMU (``fmu.export(..., sources_only=True)``) can be built by any importer that
reads it (FMPy's ``build_platform_binary`` does; FMI 2.0 importers read the ``SourceFiles``
of modelDescription.xml instead, which list the same files).

The sources are C99, need no preprocessor definitions and include only their own folder
and the standard's headers (FMI 2.0: shipped in ``sources/``; FMI 3.0: supplied by the
importer, as section 2.5.1.4 of FMI 3.0 requires).  The one library is the C math library.

References
----------
FMI 3.0.2 standard (Modelica Association, 2024), section 2.5.1.4 "Directory sources" and
``fmi3BuildDescription.xsd``.
"""

from __future__ import annotations

__all__ = ["build_description_xml"]


def build_description_xml(model_identifier: str, source_files: tuple[str, ...]) -> str:
    """Text of ``sources/buildDescription.xml``.

    Parameters
    ----------
    model_identifier : str
        The FMU's modelIdentifier (a C identifier).
    source_files : tuple of str
        The .c files under ``sources/``.

    Returns
    -------
    str
    """
    files = "".join(f'      <SourceFile name="{name}"/>\n' for name in source_files)
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<fmiBuildDescription fmiVersion="3.0">\n'
            f'  <BuildConfiguration modelIdentifier="{model_identifier}"'
            ' description="C99 sources of the flexsat LTI model; no preprocessor definitions">\n'
            '    <SourceFileSet language="C99">\n'
            f"{files}"
            '      <IncludeDirectory name="."/>\n'
            "    </SourceFileSet>\n"
            '    <Library name="m" external="true" description="the C math library"/>\n'
            "  </BuildConfiguration>\n"
            "</fmiBuildDescription>\n")
