#!/usr/bin/perl
# The include direction and file loops of the source tree (docs/design.md §5).
#
#   perl tests/lint/layers.pl SOURCE_DIR
#
# Every #include of a C/C++ file under include/, core/, plugins/, engine/, io/, common/, cli/ and
# python/
# is resolved
# to a file of the tree (quoted: beside the including file, then under the include roots below;
# <nprfx/...>: under include/; other <...> are the system's and not followed). Two rules:
#   1. Direction: a file's folder is one layer of the table below; it may include files of its
#      own layer and of the layers its row names, nothing else. A quoted include that resolves
#      to no file of the tree is an error too (a stale include would hide an edge).
#   2. No loops: a module is a file's path without its extension (foo.c + foo.h); the modules'
#      include graph must have no cycle, so that "who calls whom" reads one way.
# Prints each violation with the file and line and exits 1; prints a summary and exits 0 when
# there is none. Only perl's core language is used (perl-base is on every Debian system).
use strict;
use warnings;

my $root = shift @ARGV or die "usage: perl layers.pl SOURCE_DIR\n";
$root =~ s{/+$}{};

# Layers: file or folder (the file itself, else the longest folder prefix wins) => [layer name, layers it may include besides its own].
# The core families sit side by side on core/base: one family never includes another, except
# pam, whose pam-splat scatters its strokes with gabor-splat's anchored points
# (core/gabor/internal_scatter.h). Node descriptors use the families and their support code. The
# graph engine (engine/) and the image I/O library (io/) use only the public headers: the
# engine reaches nodes through the registry and files through an nprfx_io. The front ends (the
# runner, the OpenFX adapter, the Python module) use the public API, the engine, io/ and
# common/, and never each other. Inside the runner, lower folders never include higher ones: util, farm and host
# projects, commands, main.c.
my @FAMILIES = qw(noise gabor stipple pam looks motion);
# The runner's folders, lowest first: each includes only those before it (main.c all of them).
my @CLI = qw(cli/util cli/farm cli/host cli/commands);
# The engine's files are its own: front ends reach it through nprfx/graph.h, and of its private
# headers only engine_util.h (the clocks, strdup, the parallel copy: one of each in the tree).
my @LIBS = ('public', 'common', 'engine-util', 'io');
my %LAYERS = (
    'include/nprfx'   => ['public', []],
    'core/base'       => ['base', ['public']],
    'core/noise'      => ['noise', ['public', 'base']],
    'core/gabor'      => ['gabor', ['public', 'base']],
    'core/stipple'    => ['stipple', ['public', 'base']],
    'core/pam'        => ['pam', ['public', 'base', 'gabor']],
    'core/looks'      => ['looks', ['public', 'base']],
    'core/motion'     => ['motion', ['public', 'base']],
    'plugins/support' => ['support', ['public', 'base', @FAMILIES]],
    'plugins'         => ['nodes', ['public', 'base', @FAMILIES, 'support']],
    'engine'          => ['engine', ['public', 'engine-util']],
    'engine/engine_util.h' => ['engine-util', ['public']],
    'io'              => ['io', ['public']],
    'common'          => ['common', ['public']],
    'plugins/ofx'     => ['ofx', ['public', 'support', 'common']],
    'cli'             => ['cli', [@LIBS, @CLI]],
    'python'          => ['python', [@LIBS]],
    'cli/util'        => ['cli/util', [@LIBS]],
    'cli/farm'        => ['cli/farm', [@LIBS, 'cli/util']],
    'cli/host'        => ['cli/host', [@LIBS, 'cli/util']],
    'cli/commands'    => ['cli/commands', [@LIBS, @CLI[0 .. 2]]],
);
# Roots a quoted include is looked up under after the including file's own folder.
my @ROOTS = ('include', 'core', 'plugins', 'common', 'cli', '.');

sub layer_of {
    my ($path) = @_;
    return ($LAYERS{$path}[0], $path) if exists $LAYERS{$path}; # a file that is a layer of its own
    my $dir = $path =~ m{^(.*)/[^/]+$} ? $1 : '';
    while ($dir ne '') {
        return ($LAYERS{$dir}[0], $dir) if exists $LAYERS{$dir};
        $dir = $dir =~ m{^(.*)/[^/]+$} ? $1 : '';
    }
    return (undef, undef);
}

my @files;
for my $top (qw(include core plugins common engine io cli python)) {
    next unless -d "$root/$top";
    open(my $fh, '-|', 'find', "$root/$top", '-type', 'f', '(', '-name', '*.c', '-o', '-name',
         '*.h', '-o', '-name', '*.cpp', ')') or die "find: $!\n";
    while (my $f = <$fh>) {
        chomp $f;
        $f =~ s{^\Q$root\E/}{};
        push @files, $f;
    }
    close $fh;
}
@files = sort @files;
my %exists = map { $_ => 1 } @files;

sub normalize {
    my @out;
    for my $part (split m{/}, $_[0]) {
        next if $part eq '.' || $part eq '';
        if ($part eq '..') { pop @out; next; }
        push @out, $part;
    }
    return join('/', @out);
}

sub module_of { my ($p) = @_; $p =~ s/\.(c|h|cpp)$//; return $p; }

my (@errors, %edges, %edge_at);
my $count = 0;
for my $f (@files) {
    my ($layer) = layer_of($f);
    unless (defined $layer) {
        push @errors, "$f: its folder is in no layer (add it to the table in tests/lint/layers.pl)";
        next;
    }
    my %may = map { $_ => 1 } ($layer, @{ $LAYERS{ (layer_of($f))[1] }[1] });
    my $dir = $f =~ m{^(.*)/[^/]+$} ? $1 : '.';
    open(my $in, '<', "$root/$f") or die "$f: $!\n";
    my $line = 0;
    while (my $text = <$in>) {
        $line++;
        my ($kind, $name);
        if ($text =~ /^\s*#\s*include\s*"([^"]+)"/) { ($kind, $name) = ('q', $1); }
        elsif ($text =~ /^\s*#\s*include\s*<(nprfx\/[^>]+)>/) { ($kind, $name) = ('a', $1); }
        else { next; }
        $count++;
        my @candidates = $kind eq 'q' ? ("$dir/$name", map { "$_/$name" } @ROOTS) : ("include/$name");
        my ($target) = grep { $exists{$_} } map { normalize($_) } @candidates;
        unless (defined $target) {
            push @errors, "$f:$line: #include \"$name\" is no file of the tree";
            next;
        }
        my ($tlayer) = layer_of($target);
        unless ($may{$tlayer}) {
            push @errors, "$f:$line: includes $target: layer '$layer' may not include layer "
                . "'$tlayer' (it may include: " . join(', ', sort keys %may) . ")";
        }
        my ($a, $b) = (module_of($f), module_of($target));
        next if $a eq $b;
        $edges{$a}{$b} = 1;
        $edge_at{"$a $b"} //= "$f:$line";
    }
    close $in;
}

# Cycles: Tarjan's strongly connected components, iteratively; each component of more than one
# module is a loop, printed with one include line per edge along a cycle through it.
my %mods = map { module_of($_) => 1 } @files;
my ($index, @stack, %on, %idx, %low, @sccs) = (0);
for my $start (sort keys %mods) {
    next if exists $idx{$start};
    my @work = ([$start, [sort keys %{ $edges{$start} // {} }]]);
    $idx{$start} = $low{$start} = $index++;
    push @stack, $start;
    $on{$start} = 1;
    while (@work) {
        my ($v, $next) = @{ $work[-1] };
        if (@$next) {
            my $w = shift @$next;
            if (!exists $idx{$w}) {
                $idx{$w} = $low{$w} = $index++;
                push @stack, $w;
                $on{$w} = 1;
                push @work, [$w, [sort keys %{ $edges{$w} // {} }]];
            } elsif ($on{$w}) {
                $low{$v} = $idx{$w} if $idx{$w} < $low{$v};
            }
            next;
        }
        pop @work;
        if (@work) {
            my $u = $work[-1][0];
            $low{$u} = $low{$v} if $low{$v} < $low{$u};
        }
        if ($low{$v} == $idx{$v}) {
            my @scc;
            while (1) {
                my $w = pop @stack;
                delete $on{$w};
                push @scc, $w;
                last if $w eq $v;
            }
            push @sccs, [sort @scc] if @scc > 1;
        }
    }
}
for my $scc (@sccs) {
    my %in = map { $_ => 1 } @$scc;
    # a cycle: walk from the first module along edges inside the component until it returns
    my @path = ($scc->[0]);
    my %seen = ($scc->[0] => 0);
    while (1) {
        my ($n) = grep { $in{$_} } sort keys %{ $edges{ $path[-1] } };
        if (exists $seen{$n}) { @path = (@path[$seen{$n} .. $#path], $n); last; }
        $seen{$n} = scalar @path;
        push @path, $n;
    }
    my @steps = map { $edge_at{"$path[$_] $path[$_ + 1]"} . " -> $path[$_ + 1]" } 0 .. $#path - 1;
    push @errors, "loop between files: " . join(' -> ', @path) . "\n    " . join("\n    ", @steps);
}

if (@errors) {
    print "$_\n" for @errors;
    printf "%d problem%s in %d files (%d includes)\n", scalar @errors, @errors == 1 ? '' : 's',
        scalar @files, $count;
    exit 1;
}
printf "layers ok: %d files, %d includes, %d modules, no loop\n", scalar @files, $count,
    scalar keys %mods;
exit 0;
