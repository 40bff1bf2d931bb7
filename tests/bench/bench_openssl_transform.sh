#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# bench_openssl_transform: what the OpenSSL 3 calls of Fast DDS 2.9's AES-GCM-GMAC transform cost
# per protected message on this machine (docs/security.md, "Camera-scoped
# partitions and where the secure latency goes"): the session key a receiver derives again for
# every message (HMAC-SHA256 through
# a new EVP_PKEY), an AES-256-GCM pass over 300 bytes with a new cipher context (what both sides
# do), and the same pass with one context kept. Needs gcc and libssl-dev.
#   tests/bench/bench_openssl_transform.sh [ITERATIONS=20000]
set -euo pipefail
work="$(mktemp -d /tmp/bench-openssl-XXXXXX)"
trap 'rm -rf "$work"' EXIT
cat >"$work/transform.c" <<'C'
#include <openssl/evp.h>
#include <openssl/rand.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
static double now(void){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return t.tv_sec+t.tv_nsec*1e-9;}
int main(int argc,char**argv){(void)argc;
  unsigned char key[32]={1},salt[32]={2},out[64],iv[12]={0},buf[300]={0},enc[400],tag[16];size_t n=32;int a,b;
  const int N=atoi(argv[1]); double t0=now();
  for(int i=0;i<N;i++){ // session key: HMAC-SHA256 keyed by the master key, as compute_sessionkey
    EVP_PKEY*k=EVP_PKEY_new_mac_key(EVP_PKEY_HMAC,NULL,key,32);EVP_MD_CTX*c=EVP_MD_CTX_create();
    EVP_DigestSignInit(c,NULL,EVP_sha256(),NULL,k);EVP_DigestSignUpdate(c,salt,32);EVP_DigestSignFinal(c,out,&n);
    EVP_PKEY_free(k);EVP_MD_CTX_destroy(c);}
  double t1=now();
  for(int i=0;i<N;i++){ // one AES-256-GCM encryption of a 300-byte payload with a fresh context
    RAND_bytes(iv+4,8);EVP_CIPHER_CTX*e=EVP_CIPHER_CTX_new();EVP_EncryptInit(e,EVP_aes_256_gcm(),key,iv);
    EVP_EncryptUpdate(e,enc,&a,buf,300);EVP_EncryptFinal(e,enc+a,&b);EVP_CIPHER_CTX_ctrl(e,EVP_CTRL_GCM_GET_TAG,16,tag);
    EVP_CIPHER_CTX_free(e);}
  double t2=now();
  EVP_CIPHER_CTX*r=EVP_CIPHER_CTX_new();EVP_EncryptInit_ex(r,EVP_aes_256_gcm(),NULL,key,NULL);
  double t3=now();
  for(int i=0;i<N;i++){ // the same with one context kept, only the IV set per message
    iv[11]=(unsigned char)i;EVP_EncryptInit_ex(r,NULL,NULL,NULL,iv);
    EVP_EncryptUpdate(r,enc,&a,buf,300);EVP_EncryptFinal_ex(r,enc+a,&b);EVP_CIPHER_CTX_ctrl(r,EVP_CTRL_GCM_GET_TAG,16,tag);}
  double t4=now();
  printf("session key (HMAC-SHA256, new PKEY): %.2f us; AES-256-GCM 300 B with new context + IV: %.2f us; kept context: %.2f us\n",(t1-t0)/N*1e6,(t2-t1)/N*1e6,(t4-t3)/N*1e6);
  return 0;}
C
gcc -O2 -o "$work/transform" "$work/transform.c" -lcrypto
"$work/transform" "${1:-20000}"
