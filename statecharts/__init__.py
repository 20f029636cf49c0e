"""motionchart statecharts: spec loader, expression language, IR, engine and scan semantics."""
