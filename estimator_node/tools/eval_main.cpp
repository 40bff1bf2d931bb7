// SPDX-License-Identifier: Apache-2.0
// placeholder during bring-up; replaced before landing
int main() { return 1; }
