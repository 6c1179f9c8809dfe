"""Runs a script of `nprfx host-project --natron-script` as Natron 2.5 does (no __file__, the
current folder wherever the user is) against a stand-in for Natron's Python API, and prints what
the script asked of it: "reader PATH", "writer PATH", "node PLUGIN NAME", and every line the script
printed itself. A wrong call fails as Natron's would: connecting a non-node raises TypeError.
Choice params offer Natron 2.5's options for a Write node's formatType (input, project, fixed) and
for a Shuffle's outputR..outputA (A.r .. A.a, 0, 1, B.r .. B.a, then the plate's layers, which the
stand-in does not know: any other label), and take any label asked for elsewhere; a Shuffle's
choice prints "choice NODE PARAM OPTION" ("*" for a layer).
usage: python3 natron_stub.py SCRIPT.py"""
import sys
import types


class AnyText(str):
    """An option or a clip label the stand-in does not know: equal to whatever is asked."""

    def __eq__(self, other):
        return True

    def __hash__(self):
        return 0

    def endswith(self, *args):
        return True


SHUFFLE = ["A.r", "A.g", "A.b", "A.a", "0", "1", "B.r", "B.g", "B.b", "B.a"]


class Param:
    def __init__(self, name, node=None):
        self.name = name
        self.node = node
        self.options = [AnyText("*")]
        if name == "formatType":
            self.options = ["input", "project", "fixed"]
        elif name in ("outputR", "outputG", "outputB", "outputA"):
            self.options = SHUFFLE + [AnyText("*")]

    def getScriptName(self):
        return self.name

    def getNumOptions(self):
        return len(self.options)

    def getOption(self, i):
        return self.options[i]

    def setValue(self, *v):
        if self.name.startswith("output") and len(self.options) > 1:
            print("choice %s %s %s" % (self.node.getScriptName(), self.name,
                                       str.__str__(self.options[v[0]])))

    def set(self, *v):
        pass


class Node:
    def __init__(self, kind):
        self.kind = kind
        self.params = {}

    def setScriptName(self, name):
        self.name = name

    def getScriptName(self):
        return getattr(self, "name", "?")

    def getParam(self, name):
        return self.params.setdefault(name, Param(name, self))

    def getMaxInputCount(self):
        return 1

    def getInputLabel(self, i):
        return AnyText("*")

    def connectInput(self, i, src):
        if not isinstance(src, Node):
            raise TypeError("connectInput(): argument 2 must be Effect, not %s" % type(src).__name__)
        return True


class App:
    def getProjectParam(self, name):
        return Param(name)

    def addFormat(self, text):
        pass

    def createReader(self, path):
        print("reader " + path)
        return Node("Read")

    def createWriter(self, path):
        print("writer " + path)
        return Node("Write")

    def createNode(self, plugin):
        print("node " + plugin)
        return Node(plugin)


sys.modules["NatronEngine"] = types.ModuleType("NatronEngine")
source = open(sys.argv[1]).read()
exec(compile(source, sys.argv[1], "exec"), {"__name__": "__main__", "app": App()})
