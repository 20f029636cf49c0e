"""motionchart checker: the command line, scenario runner and (later) the model checker."""
