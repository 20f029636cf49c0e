"""The bundled motionchart specification (YAML data and its JSON Schema).

Importable as ``motionchart_spec`` once the project is installed; the YAML files are
package data.  Read it through :func:`statecharts.loader.load_spec`.
"""
